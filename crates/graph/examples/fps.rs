//! Times exact FPS, fast (kd-tree) FPS and weighted sampling on points sampled from a bumpy
//! sphere, and writes the points as `.npy` so `benches/peers/fps_peers.py` can time `fpsample`
//! on the very same input.
//!
//! ```text
//! cargo run --release -p meshgnn-graph --example fps -- [OUT_DIR] [N,N,...] [RATIO,RATIO,...]
//! ```
//! Defaults: `bench-data`, `100000,1000000`, `0.01,0.05,0.2`. Exact FPS runs only when
//! `N·M <= 2e10` (it is O(N·M)). Output: one line per run, `N M method seconds`, and
//! `fps_{N}_{M}.u32` with fast FPS's indices (start 0) for comparison with fpsample.

use std::io::Write;
use std::time::Instant;

use meshgnn_geometry::{icosphere, sample_surface};
use meshgnn_graph::{
    FpsStart, farthest_point_sampling, fast_farthest_point_sampling, weighted_sampling,
};

/// Exact FPS is skipped above this many distance evaluations.
const EXACT_LIMIT: f64 = 2e10;

/// `n` points on a sphere with radial bumps `1 + 0.15·sin 6x·sin 6y·sin 6z`.
fn bumpy_sphere_points(n: usize, seed: u64) -> Result<Vec<[f32; 3]>, Box<dyn std::error::Error>> {
    let sphere = icosphere(5);
    let bumped: Vec<[f32; 3]> = sphere
        .vertices()
        .iter()
        .map(|p| {
            let r = 1.0 + 0.15 * (6.0 * p[0]).sin() * (6.0 * p[1]).sin() * (6.0 * p[2]).sin();
            [p[0] * r, p[1] * r, p[2] * r]
        })
        .collect();
    let mesh = sphere.with_vertices(bumped)?;
    Ok(sample_surface(&mesh, n, seed)?.points)
}

/// Writes `points: #N×3` as a little-endian `float32` `.npy` array of shape `(N, 3)`.
fn write_npy(path: &std::path::Path, points: &[[f32; 3]]) -> std::io::Result<()> {
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, 3), }}",
        points.len()
    );
    // Magic (6) + version (2) + header length (2) + header + '\n', padded to 64 bytes.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.next_multiple_of(64) - total));
    header.push('\n');
    let mut bytes = Vec::with_capacity(total + 64 + points.len() * 12);
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for p in points {
        for x in p {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    std::fs::File::create(path)?.write_all(&bytes)
}

fn parse_list<T: std::str::FromStr>(arg: Option<String>, default: &str) -> Vec<T> {
    arg.as_deref()
        .unwrap_or(default)
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| "bench-data".into()));
    let sizes: Vec<usize> = parse_list(args.next(), "100000,1000000");
    let ratios: Vec<f64> = parse_list(args.next(), "0.01,0.05,0.2");
    std::fs::create_dir_all(&out)?;
    println!("threads {}", rayon::current_num_threads());
    for &n in &sizes {
        let points = bumpy_sphere_points(n, 1)?;
        write_npy(&out.join(format!("points_{n}.npy")), &points)?;
        let scores: Vec<f32> = points.iter().map(|p| 1.0 + p[0] * p[0]).collect();
        for &ratio in &ratios {
            let m = ((n as f64 * ratio).round() as usize).max(1);
            let t = Instant::now();
            let fast = fast_farthest_point_sampling(&points, m, FpsStart::Index(0))?;
            println!("{n} {m} fast_fps {:.4}", t.elapsed().as_secs_f64());
            let bytes: Vec<u8> = fast.iter().flat_map(|i| i.to_le_bytes()).collect();
            std::fs::write(out.join(format!("fps_{n}_{m}.u32")), bytes)?;
            if (n as f64) * (m as f64) <= EXACT_LIMIT {
                let t = Instant::now();
                let exact =
                    farthest_point_sampling(points.as_flattened(), 3, m, FpsStart::Index(0))?;
                println!("{n} {m} exact_fps {:.4}", t.elapsed().as_secs_f64());
                if exact != fast {
                    return Err(format!("fast FPS differs from exact FPS at N={n}, M={m}").into());
                }
            } else {
                println!("{n} {m} exact_fps skipped");
            }
            let t = Instant::now();
            let picked = weighted_sampling(&scores, m, 7)?;
            println!("{n} {m} weighted {:.4}", t.elapsed().as_secs_f64());
            if picked.len() != m {
                return Err("weighted sampling returned the wrong count".into());
            }
        }
    }
    Ok(())
}
