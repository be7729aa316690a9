//! The design-card comparison of docs/io.md ("Design-card crates"): meshgnn's OBJ reader vs
//! tobj (speed on the 1.31M-triangle OBJ, behaviour on malformed files), the former cyclic
//! Jacobi 3×3 symmetric eigen-solver vs nalgebra, and QEM's closed-form placement solve vs
//! nalgebra. A separate package so that tobj never enters the workspace.
//!
//! `cargo run --release -- quadric ../../../data-fixtures/examples/creature.ply`, `-- eigen`,
//! `-- obj DIR` (writes `DIR/io_1m.obj` first when missing).
use meshgnn_geometry::{MeshFormat, icosphere, read_mesh, read_mesh_bytes, write_mesh};
use rand::{Rng, SeedableRng};
use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn best<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::MAX;
    let mut out = None;
    for _ in 0..n {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.unwrap())
}

fn tobj_opts() -> tobj::LoadOptions {
    tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    }
}

fn tobj_counts(r: tobj::LoadResult) -> Result<(usize, usize), String> {
    match r {
        Ok((models, _)) => Ok((
            models.iter().map(|m| m.mesh.positions.len() / 3).sum(),
            models.iter().map(|m| m.mesh.indices.len() / 3).sum(),
        )),
        Err(e) => Err(format!("{e:?}")),
    }
}

fn tobj_bytes(bytes: Vec<u8>) -> Result<(usize, usize), String> {
    let mut reader = std::io::BufReader::new(std::io::Cursor::new(bytes));
    tobj_counts(tobj::load_obj_buf(&mut reader, &tobj_opts(), |_| {
        Err(tobj::LoadError::OpenFileFailed)
    }))
}

fn with_timeout<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> String
where
    T: std::fmt::Debug,
{
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
        let _ = tx.send(match r {
            Ok(v) => format!("{v:?}"),
            Err(_) => "PANIC".to_string(),
        });
    });
    match rx.recv_timeout(Duration::from_secs(10)) {
        Ok(s) => s,
        Err(_) => "HANG (>10 s)".to_string(),
    }
}

fn obj_section(dir: &Path) {
    let path = dir.join("io_1m.obj");
    if !path.exists() {
        // As crates/geometry/examples/write_bench_mesh.rs.
        let sphere = icosphere(8);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let noisy = sphere
            .vertices()
            .iter()
            .map(|p| p.map(|x| x + rng.random_range(-1e-3f32..1e-3)))
            .collect();
        let mesh = sphere.with_vertices(noisy).unwrap();
        write_mesh(&path, &mesh).unwrap();
    }
    let size = std::fs::metadata(&path).unwrap().len() as f64 / (1024.0 * 1024.0);
    let (t_own, own) = best(5, || read_mesh(&path).unwrap());
    let (t_tobj, tm) = best(5, || tobj_counts(tobj::load_obj(&path, &tobj_opts())));
    println!(
        "OBJ {:.1} MiB: own {:.3} s ({} v, {} f)  tobj {:.3} s ({:?})",
        size,
        t_own,
        own.vertex_count(),
        own.face_count(),
        t_tobj,
        tm
    );
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("empty file", b"".to_vec()),
        (
            "face index out of range",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(),
        ),
        (
            "face index 0",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".to_vec(),
        ),
        (
            "negative index before start",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -5 1 2\n".to_vec(),
        ),
        (
            "index overflowing i64",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n".to_vec(),
        ),
        (
            "non-numeric coordinate",
            b"v 0 x 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "missing coordinate",
            b"v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "NaN coordinate",
            b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "inf coordinate",
            b"v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "two-corner face",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n".to_vec(),
        ),
        (
            "non-numeric index",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 3\n".to_vec(),
        ),
        (
            "truncated mid-line",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0.5 0.".to_vec(),
        ),
        (
            "invalid UTF-8",
            b"v 0 0 0\nv 1 0 0\nv 0 1 \xff\xfe\nf 1 2 3\n".to_vec(),
        ),
        (
            "binary garbage",
            (0..4096u32)
                .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
                .collect(),
        ),
        (
            "vt index out of range",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/7 3/1\n".to_vec(),
        ),
        (
            "vn index out of range",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//4\n".to_vec(),
        ),
    ];
    for (name, bytes) in cases {
        let b2 = bytes.clone();
        let own = with_timeout(move || {
            read_mesh_bytes(&b2, MeshFormat::Obj)
                .map(|m| (m.vertex_count(), m.face_count()))
                .map_err(|e| e.to_string())
        });
        let theirs = with_timeout(move || tobj_bytes(bytes));
        println!("| {name} | {own} | {theirs} |");
    }
}

fn eigen_section() {
    // Covariances of the 1-rings of a noisy icosphere(7): the near-flat neighbourhoods of the
    // curvature hot loop.
    let sphere = icosphere(7);
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let v: Vec<[f64; 3]> = sphere
        .vertices()
        .iter()
        .map(|p| p.map(|x| f64::from(x) + rng.random_range(-1e-3..1e-3)))
        .collect();
    let mut rings = vec![Vec::new(); v.len()];
    for t in sphere.triangles() {
        for k in 0..3 {
            rings[t[k] as usize].push(t[(k + 1) % 3] as usize);
        }
    }
    let covs: Vec<[[f64; 3]; 3]> = rings
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let pts: Vec<[f64; 3]> = std::iter::once(i)
                .chain(r.iter().copied())
                .map(|j| v[j])
                .collect();
            let n = pts.len() as f64;
            let mut c = [0.0; 3];
            for p in &pts {
                for k in 0..3 {
                    c[k] += p[k] / n;
                }
            }
            let mut m = [[0.0; 3]; 3];
            for p in &pts {
                for a in 0..3 {
                    for b in 0..3 {
                        m[a][b] += (p[a] - c[a]) * (p[b] - c[b]) / n;
                    }
                }
            }
            m
        })
        .collect();
    let (t_own, own) = best(5, || {
        covs.iter().map(|&m| jacobi_eigen3(m)).collect::<Vec<_>>()
    });
    let (t_na, na) = best(5, || {
        covs.iter()
            .map(|m| {
                let e = nalgebra::Matrix3::from_fn(|r, c| m[r][c]).symmetric_eigen();
                let mut order = [0usize, 1, 2];
                order.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
                (
                    order.map(|i| e.eigenvalues[i]),
                    order.map(|i| [0, 1, 2].map(|r| e.eigenvectors[(r, i)])),
                )
            })
            .collect::<Vec<_>>()
    });
    let residual = |all: &[([f64; 3], [[f64; 3]; 3])]| {
        let mut worst = 0.0f64;
        for (m, (vals, vecs)) in covs.iter().zip(all) {
            let scale = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            for (l, x) in vals.iter().zip(vecs) {
                for r in 0..3 {
                    let ax: f64 = (0..3).map(|c| m[r][c] * x[c]).sum();
                    worst = worst.max((ax - l * x[r]).abs() / scale);
                }
            }
        }
        worst
    };
    let mut normal_bits_differ = 0;
    let mut worst_angle = 0.0f64;
    for (a, b) in own.iter().zip(&na) {
        if a.1[0] != b.1[0] && a.1[0] != b.1[0].map(|x| -x) {
            normal_bits_differ += 1;
        }
        let d: f64 = (0..3).map(|k| a.1[0][k] * b.1[0][k]).sum::<f64>().abs();
        worst_angle = worst_angle.max(d.min(1.0).acos());
    }
    println!(
        "eigen3 x{}: former Jacobi {:.4} s ({:.1} ns each, worst rel. residual {:.1e})  nalgebra {:.4} s ({:.1} ns each, worst {:.1e}); normals with other bits {} of {}, worst angle {:.1e} rad",
        covs.len(),
        t_own,
        t_own * 1e9 / covs.len() as f64,
        residual(&own),
        t_na,
        t_na * 1e9 / covs.len() as f64,
        residual(&na),
        normal_bits_differ,
        covs.len(),
        worst_angle
    );
}

/// The cyclic Jacobi solver `symmetric_eigen3` used before nalgebra (commit 04c27e9).
fn jacobi_eigen3(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut m = [
        [a[0][0], a[0][1], a[0][2]],
        [a[0][1], a[1][1], a[1][2]],
        [a[0][2], a[1][2], a[2][2]],
    ];
    // Columns of v are the eigenvectors.
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if scale > 0.0 && scale.is_finite() {
        for _sweep in 0..32 {
            let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
            if off <= 1e-300 || off <= f64::EPSILON * 1e-3 * scale {
                break;
            }
            for (p, q) in [(0, 1), (0, 2), (1, 2)] {
                if m[p][q] == 0.0 {
                    continue;
                }
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // m ← Jᵀ m J with the rotation J in the (p, q) plane.
                for row in &mut m {
                    let (mkp, mkq) = (row[p], row[q]);
                    row[p] = c * mkp - s * mkq;
                    row[q] = s * mkp + c * mkq;
                }
                let (rp, rq) = (m[p], m[q]);
                m[p] = [0, 1, 2].map(|k| c * rp[k] - s * rq[k]);
                m[q] = [0, 1, 2].map(|k| s * rp[k] + c * rq[k]);
                for row in &mut v {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| m[i][i].total_cmp(&m[j][j]));
    let values = order.map(|i| m[i][i]);
    let vectors = order.map(|i| [v[0][i], v[1][i], v[2][i]]);
    (values, vectors)
}

/// Own closed form, as crates/graph/src/qem/quadric.rs `optimal_point`.
#[inline]
fn own_optimal(a: [f64; 6], b: [f64; 3]) -> Option<[f64; 3]> {
    let [a00, a01, a02, a11, a12, a22] = a;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    let scale = (a00 + a11 + a22) / 3.0;
    let threshold = 1e-10 * scale * scale * scale;
    if scale.is_nan() || scale <= 0.0 || det.is_nan() || det.abs() <= threshold {
        return None;
    }
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    let [b0, b1, b2] = b;
    let inv = -1.0 / det;
    let v = [
        inv * (c00 * b0 + c01 * b1 + c02 * b2),
        inv * (c01 * b0 + c11 * b1 + c12 * b2),
        inv * (c02 * b0 + c12 * b1 + c22 * b2),
    ];
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// nalgebra with the same conditioning test: the 3x3 `A v = -b` by LU (the 4x4 GH97 system's
/// upper block) and by the closed-form inverse nalgebra uses for 3x3.
#[inline]
fn nalgebra_optimal(a: [f64; 6], b: [f64; 3], lu: bool) -> Option<[f64; 3]> {
    let [a00, a01, a02, a11, a12, a22] = a;
    let m = nalgebra::Matrix3::new(a00, a01, a02, a01, a11, a12, a02, a12, a22);
    let scale = (a00 + a11 + a22) / 3.0;
    let det = m.determinant();
    if scale.is_nan() || scale <= 0.0 || det.is_nan() || det.abs() <= 1e-10 * scale * scale * scale
    {
        return None;
    }
    let rhs = nalgebra::Vector3::new(-b[0], -b[1], -b[2]);
    let v = if lu {
        m.lu().solve(&rhs)?
    } else {
        m.try_inverse()? * rhs
    };
    let v = [v[0], v[1], v[2]];
    v.iter().all(|x| x.is_finite()).then_some(v)
}

fn quadric_section(creature: &Path) {
    let mesh = read_mesh(creature).unwrap();
    let p: Vec<[f64; 3]> = mesh.vertices().iter().map(|q| q.map(f64::from)).collect();
    let mut qa = vec![[0.0f64; 6]; p.len()];
    let mut qb = vec![[0.0f64; 3]; p.len()];
    let mut edges = Vec::new();
    for t in mesh.triangles() {
        let [x, y, z] = t.map(|i| p[i as usize]);
        let u = [y[0] - x[0], y[1] - x[1], y[2] - x[2]];
        let w = [z[0] - x[0], z[1] - x[1], z[2] - x[2]];
        let n = [
            u[1] * w[2] - u[2] * w[1],
            u[2] * w[0] - u[0] * w[2],
            u[0] * w[1] - u[1] * w[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len == 0.0 {
            continue;
        }
        let area = 0.5 * len;
        let n = n.map(|c| c / len);
        let d = -(n[0] * x[0] + n[1] * x[1] + n[2] * x[2]);
        let a = [
            n[0] * n[0],
            n[0] * n[1],
            n[0] * n[2],
            n[1] * n[1],
            n[1] * n[2],
            n[2] * n[2],
        ];
        for &i in t {
            for k in 0..6 {
                qa[i as usize][k] += area * a[k];
            }
            for k in 0..3 {
                qb[i as usize][k] += area * n[k] * d;
            }
        }
        for k in 0..3 {
            let (i, j) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            edges.push((i as usize, j as usize));
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let sums: Vec<([f64; 6], [f64; 3])> = edges
        .iter()
        .map(|&(i, j)| {
            (
                std::array::from_fn(|k| qa[i][k] + qa[j][k]),
                std::array::from_fn(|k| qb[i][k] + qb[j][k]),
            )
        })
        .collect();
    let reps = 20;
    let (t_own, own) = best(5, || {
        let mut out = Vec::new();
        for _ in 0..reps {
            out = sums
                .iter()
                .map(|&(a, b)| own_optimal(a, b))
                .collect::<Vec<_>>();
        }
        out
    });
    for lu in [false, true] {
        let (t_na, na) = best(5, || {
            let mut out = Vec::new();
            for _ in 0..reps {
                out = sums
                    .iter()
                    .map(|&(a, b)| nalgebra_optimal(a, b, lu))
                    .collect::<Vec<_>>();
            }
            out
        });
        let differ = own.iter().zip(&na).filter(|(a, b)| a != b).count();
        let mut worst = 0.0f64;
        for (a, b) in own.iter().zip(&na) {
            if let (Some(a), Some(b)) = (a, b) {
                for k in 0..3 {
                    worst = worst.max((a[k] - b[k]).abs());
                }
            }
        }
        println!(
            "quadric solve x{} ({} solvable): own {:.1} ns each, nalgebra {} {:.1} ns each; results with other bits {} ({:.2}%), worst |Δ| {:.1e}",
            sums.len(),
            own.iter().filter(|x| x.is_some()).count(),
            t_own * 1e9 / (sums.len() * reps) as f64,
            if lu { "LU" } else { "try_inverse" },
            t_na * 1e9 / (sums.len() * reps) as f64,
            differ,
            100.0 * differ as f64 / sums.len() as f64,
            worst
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("all");
    if what == "all" || what == "quadric" {
        quadric_section(Path::new(&args[2]));
    }
    if what == "all" || what == "eigen" {
        eigen_section();
    }
    if what == "all" || what == "obj" {
        obj_section(Path::new(args.get(2).map_or(".", String::as_str)));
    }
}
