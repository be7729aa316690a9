//! PCA compactness of the hand set with and without articulation:
//! `cargo run -p meshgnn-data --release --example hand_pca -- [subjects] [subdivisions]`.

use meshgnn_data::{HandSetConfig, HandTemplate};
use meshgnn_losses::metrics::{Compactness, compactness};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(200);
    let level: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(3);
    let template = HandTemplate::new(level)?;
    let curve = |articulated| -> Result<Compactness, Box<dyn std::error::Error>> {
        let cfg = HandSetConfig {
            subdivisions: level,
            articulated,
            seed: 0,
            ..Default::default()
        };
        let shapes = (0..n)
            .map(|i| cfg.sample(&template, i).map(|s| s.vertices))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(compactness(&shapes)?)
    };
    let (posed, still) = (curve(true)?, curve(false)?);
    println!("| components | posed | pose-free |");
    println!("|---:|---:|---:|");
    for k in [1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50] {
        if let (Some(a), Some(b)) = (posed.cumulative.get(k - 1), still.cumulative.get(k - 1)) {
            println!("| {k} | {:.3} | {:.3} |", a, b);
        }
    }
    for f in [0.9, 0.95, 0.99] {
        println!(
            "components for {:.0} %: posed {}, pose-free {}",
            f * 100.0,
            posed.components_for(f),
            still.components_for(f)
        );
    }
    Ok(())
}
