//! How linear is the synthetic 4D face set? PCA of the expression displacements
//! (every written frame minus its subject's neutral face) — the expression-blendshape baseline
//! of thesis ch. 4.4.2 (Table 4.2), which applies PCA to exactly these motion deformations and
//! keeps as many components as the generator's latent size (64).
//!
//! ```text
//! cargo run -p meshgnn-data --profile testing --example face_displacement_pca -- [subjects] [frame_step] [seed]
//! ```
//!
//! Defaults: 60 subjects (the `synth faces` default set), every 5th frame, seed 0. The PCA is
//! fitted on the frames of the training subjects (`X`: `n × 3V`, centred on their mean; the
//! spectrum comes from the `n × n` Gram matrix `X Xᵀ`), then evaluated on the held-out test
//! subjects: each test displacement is projected on the first `k` components and the mean
//! per-vertex Euclidean error (mm) of the reconstruction is reported, as in Table 4.2.

use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par, Side};
use meshgnn_data::{Expression, FaceSetConfig, FaceTemplate};
use rayon::prelude::*;

/// One frame's displacement from its subject's neutral face, `3V` (x, y, z per vertex).
struct Frame {
    test: bool,
    expression: Expression,
    motion: f64,
    displacement: Vec<f32>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let subjects: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(60);
    let frame_step: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(5);
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(0);
    let cfg = FaceSetConfig {
        subjects,
        frame_step,
        seed,
    };
    let template = FaceTemplate::default();
    let start = Instant::now();
    let frames: Vec<Frame> = (0..subjects)
        .into_par_iter()
        .map(|i| {
            let s = cfg.subject(&template, i)?;
            let mut out = Vec::new();
            for q in &s.sequences {
                for (f, &motion) in q.frames.iter().zip(&q.motion) {
                    let displacement = f
                        .iter()
                        .zip(&s.neutral)
                        .flat_map(|(p, n)| [p[0] - n[0], p[1] - n[1], p[2] - n[2]])
                        .collect();
                    out.push(Frame {
                        test: s.split == "test",
                        expression: q.expression,
                        motion,
                        displacement,
                    });
                }
            }
            Ok(out)
        })
        .collect::<Result<Vec<_>, meshgnn_data::Error>>()?
        .into_iter()
        .flatten()
        .collect();
    let (test, train): (Vec<&Frame>, Vec<&Frame>) = frames.iter().partition(|f| f.test);
    let d = 3 * template.vertex_count();
    let (n, m) = (train.len(), test.len());
    println!(
        "{subjects} subjects ({} test), every {frame_step}th frame, seed {seed}: {n} training \
         frames, {m} test frames, {} vertices ({:.1} s)",
        cfg.test_subjects(),
        template.vertex_count(),
        start.elapsed().as_secs_f64()
    );
    if n < 2 || m == 0 {
        return Err("needs at least two training frames and one test frame".into());
    }
    // Training mean and centred data matrices.
    let mut mean = vec![0.0f64; d];
    for f in &train {
        for (a, &x) in mean.iter_mut().zip(&f.displacement) {
            *a += f64::from(x);
        }
    }
    for a in &mut mean {
        *a /= n as f64;
    }
    let centred = |rows: &[&Frame]| {
        Mat::from_fn(rows.len(), d, |i, j| {
            f64::from(rows[i].displacement[j]) - mean[j]
        })
    };
    let (x, t) = (centred(&train), centred(&test));
    // Gram matrix and its eigen-decomposition (eigenvalues ascending).
    let mut gram = Mat::<f64>::zeros(n, n);
    matmul(
        gram.as_mut(),
        Accum::Replace,
        x.as_ref(),
        x.transpose(),
        1.0 / (n - 1) as f64,
        Par::rayon(0),
    );
    let evd = gram
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| format!("eigen-decomposition failed: {e:?}"))?;
    let s = evd.S().column_vector();
    let variances: Vec<f64> = (0..n).rev().map(|i| s[i].max(0.0)).collect();
    let total: f64 = variances.iter().sum();
    let mut acc = 0.0;
    let cumulative: Vec<f64> = variances
        .iter()
        .map(|v| {
            acc += v;
            acc / total
        })
        .collect();
    let components_for = |f: f64| cumulative.iter().position(|&c| c >= f).map_or(n, |i| i + 1);
    println!(
        "components for 90 / 95 / 99 / 99.9 % of the training variance: {} / {} / {} / {}",
        components_for(0.9),
        components_for(0.95),
        components_for(0.99),
        components_for(0.999)
    );
    for k in [8, 16, 32, 64] {
        if let Some(c) = cumulative.get(k - 1) {
            println!(
                "variance outside the first {k:>2} components: {:.3e}",
                1.0 - c
            );
        }
    }
    // Principal directions u_j = Xᵀ v_j / |Xᵀ v_j| for the 64 largest eigenvalues.
    let kmax = 64.min(n - 1);
    let u_evd = evd.U();
    let v = Mat::from_fn(n, kmax, |i, j| u_evd[(i, n - 1 - j)]);
    let mut basis = Mat::<f64>::zeros(d, kmax);
    matmul(
        basis.as_mut(),
        Accum::Replace,
        x.transpose(),
        v.as_ref(),
        1.0,
        Par::rayon(0),
    );
    for j in 0..kmax {
        let norm = (0..d)
            .map(|i| basis[(i, j)] * basis[(i, j)])
            .sum::<f64>()
            .sqrt();
        if norm > 0.0 {
            for i in 0..d {
                basis[(i, j)] /= norm;
            }
        }
    }
    let mut coefficients = Mat::<f64>::zeros(m, kmax);
    matmul(
        coefficients.as_mut(),
        Accum::Replace,
        t.as_ref(),
        basis.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let test_energy: f64 = (0..m)
        .map(|i| (0..d).map(|j| t[(i, j)] * t[(i, j)]).sum::<f64>())
        .sum();
    let apex: Vec<bool> = test.iter().map(|f| f.motion >= 0.999).collect();
    println!("test subjects, reconstruction by the first k training components:");
    println!(
        "| k | mean per-vertex error, all frames (mm) | apex frames (mm) | test variance outside |"
    );
    println!("|---:|---:|---:|---:|");
    let mut per_expression = [(0.0f64, 0usize); 6];
    for k in [0, 8, 16, 64] {
        let k = k.min(kmax);
        let mut recon = Mat::<f64>::zeros(m, d);
        if k > 0 {
            matmul(
                recon.as_mut(),
                Accum::Replace,
                coefficients.as_ref().subcols(0, k),
                basis.as_ref().subcols(0, k).transpose(),
                1.0,
                Par::rayon(0),
            );
        }
        let errors: Vec<(f64, f64)> = (0..m)
            .map(|i| {
                let (mut e, mut sq) = (0.0, 0.0);
                for vtx in 0..d / 3 {
                    let r = [0, 1, 2].map(|c| t[(i, 3 * vtx + c)] - recon[(i, 3 * vtx + c)]);
                    let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                    e += r2.sqrt();
                    sq += r2;
                }
                (e / (d / 3) as f64, sq)
            })
            .collect();
        let all = errors.iter().map(|e| e.0).sum::<f64>() / m as f64;
        let apex_n = apex.iter().filter(|&&a| a).count().max(1);
        let apex_err = errors
            .iter()
            .zip(&apex)
            .filter(|(_, a)| **a)
            .map(|(e, _)| e.0)
            .sum::<f64>()
            / apex_n as f64;
        let outside = errors.iter().map(|e| e.1).sum::<f64>() / test_energy.max(f64::MIN_POSITIVE);
        println!("| {k} | {all:.3} | {apex_err:.3} | {outside:.3e} |");
        if k == kmax {
            for (f, e) in test.iter().zip(&errors) {
                let p = &mut per_expression[f.expression.index()];
                p.0 += e.0;
                p.1 += 1;
            }
        }
    }
    let row: Vec<String> = Expression::ALL
        .iter()
        .map(|e| {
            let (sum, count) = per_expression[e.index()];
            format!("{} {:.3}", e.name(), sum / count.max(1) as f64)
        })
        .collect();
    println!(
        "{kmax}-component error per expression (mm, all test frames): {}",
        row.join(", ")
    );
    println!("done in {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}
