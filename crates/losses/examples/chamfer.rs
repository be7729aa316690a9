//! Times the symmetric Chamfer distance (thesis eq. 5.6) on uniform random point sets and
//! writes the sets to disk for the peer comparison (`benches/peers/chamfer_peers.py`).
//!
//! ```text
//! cargo run --release -p meshgnn-losses --example chamfer -- [OUT_DIR] [N,N,...]
//! ```
//! Writes `OUT_DIR/chamfer_a_N.f32` and `chamfer_b_N.f32` (little-endian `f32`, N×3) and prints
//! one line per size: `N seconds forward_mean reverse_mean` (best of 3 runs).

use meshgnn_losses::metrics::chamfer_distance;
use rand::{Rng, SeedableRng, rngs::StdRng};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn random_points(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| [rng.random(), rng.random(), rng.random()])
        .collect()
}

fn write_f32(path: &Path, points: &[[f32; 3]]) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(points.len() * 12);
    for p in points {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    std::fs::File::create(path)?.write_all(&bytes)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().unwrap_or_else(|| "bench-data".into()));
    let sizes = args.next().unwrap_or_else(|| "100000,1000000".into());
    std::fs::create_dir_all(&out)?;
    println!("threads {}", rayon::current_num_threads());
    for n in sizes.split(',') {
        let n: usize = n.trim().parse()?;
        let a = random_points(n, 1);
        let b = random_points(n, 2);
        write_f32(&out.join(format!("chamfer_a_{n}.f32")), &a)?;
        write_f32(&out.join(format!("chamfer_b_{n}.f32")), &b)?;
        let mut best = f64::INFINITY;
        let mut cd = None;
        for _ in 0..3 {
            let t = Instant::now();
            cd = Some(chamfer_distance(&a, &b)?);
            best = best.min(t.elapsed().as_secs_f64());
        }
        if let Some(cd) = cd {
            println!(
                "{n} {best:.6} {:.9e} {:.9e}",
                cd.forward_mean, cd.reverse_mean
            );
        }
    }
    Ok(())
}
