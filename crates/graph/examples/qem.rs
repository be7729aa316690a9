//! QEM decimation of a mesh file, timed, with its distance to the input.
//!
//! ```text
//! cargo run --release -p meshgnn-graph --example qem -- IN.ply --ratio 0.1 [--meshopt]
//! cargo run --release -p meshgnn-graph --example qem -- --make-bumpy 8 OUT.ply
//! ```
//! `--out OUT.ply` writes the simplified mesh (to compare outputs across versions).
//! `--no-metrics` skips the distances (for peak-RSS measurements of the decimation alone).
//! `--meshopt` runs meshoptimizer's `simplify` (LockBorder, no error limit) instead, for
//! comparison. `--make-bumpy S OUT` writes the benchmark mesh: `icosphere(S)` with smooth,
//! deterministic bumps. Distances: every mesh is sampled on a barycentric lattice of spacing
//! `sqrt(area / 2·10⁶)`; the symmetric Hausdorff and Chamfer distances (mean nearest-sample
//! distance, summed over both directions) are reported relative to the input's bounding-box
//! diagonal, with the mean squared distance (both directions averaged) relative to the
//! diagonal squared. `--faces N` asks for N faces instead of a ratio. `--density K` (default 4) samples `K` times more densely (spacing `/ sqrt(K)`):
//! at `K = 1` the 1.31M-face input's faces (longest edge < 3 spacings) get no interior lattice
//! point, so its samples are its vertices alone, and an output whose vertices are input
//! vertices (meshoptimizer) gets distance 0 on all of them (docs/qem.md, "Chamfer at 10%").

use std::time::Instant;

use meshgnn_geometry::{SpatialIndex, TriMesh, icosphere, read_mesh, write_mesh};
use meshgnn_graph::{DecimationOptions, Target, decimate};
use rayon::prelude::*;

/// The benchmark surface: a sphere with smooth bumps (shared with `benches/qem.rs`).
fn bumpy_sphere(subdivisions: u32) -> Result<TriMesh, meshgnn_geometry::Error> {
    let sphere = icosphere(subdivisions);
    let vertices = sphere
        .vertices()
        .iter()
        .map(|p| {
            let [x, y, z] = p.map(f64::from);
            let r = 1.0
                + 0.05 * (5.0 * x).sin() * (7.0 * y).sin() * (3.0 * z).sin()
                + 0.02 * (17.0 * x + 11.0 * y).sin();
            [x * r, y * r, z * r].map(|c| c as f32)
        })
        .collect();
    sphere.with_vertices(vertices)
}

/// Lattice samples of every face, spacing `h`, plus the vertices. A face listed again (the
/// same three vertices) is sampled once: the distance is between surfaces, and a surface
/// listed twice is not twice as much surface.
fn samples(vertices: &[[f32; 3]], triangles: &[[u32; 3]], h: f64) -> Vec<[f32; 3]> {
    let mut out: Vec<[f32; 3]> = vertices.to_vec();
    let mut seen = std::collections::HashSet::new();
    let distinct: Vec<[u32; 3]> = triangles
        .iter()
        .filter(|t| {
            let mut key = **t;
            key.sort_unstable();
            seen.insert(key)
        })
        .copied()
        .collect();
    let per_face: Vec<Vec<[f32; 3]>> = distinct
        .par_iter()
        .map(|t| {
            let p = t.map(|v| vertices[v as usize].map(f64::from));
            let longest = (0..3)
                .map(|i| {
                    let (a, b) = (p[i], p[(i + 1) % 3]);
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
                })
                .fold(0.0, f64::max);
            let s = ((longest / h).ceil() as usize).clamp(3, 64);
            let mut pts = Vec::new();
            for i in 1..s {
                for j in 1..s - i {
                    let (u, v) = (i as f64 / s as f64, j as f64 / s as f64);
                    let w = 1.0 - u - v;
                    pts.push(std::array::from_fn(|k| {
                        (w * p[0][k] + u * p[1][k] + v * p[2][k]) as f32
                    }));
                }
            }
            pts
        })
        .collect();
    out.extend(per_face.into_iter().flatten());
    out
}

/// (max, mean, mean squared) distance from each point of `from` to its nearest point of `to`.
fn one_sided(
    from: &[[f32; 3]],
    to: &[[f32; 3]],
) -> Result<(f64, f64, f64), meshgnn_geometry::Error> {
    let index = SpatialIndex::new(to)?;
    let d: Vec<f64> = from
        .par_iter()
        .map_init(Vec::new, |found, p| {
            index.nearest(p, 1, None, found);
            found
                .first()
                .map_or(f64::INFINITY, |&(d, _)| f64::from(d).sqrt())
        })
        .collect();
    let max = d.iter().copied().fold(0.0, f64::max);
    let n = d.len().max(1) as f64;
    let mean_squared = d.iter().map(|x| x * x).sum::<f64>() / n;
    Ok((max, d.iter().sum::<f64>() / n, mean_squared))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--make-bumpy") {
        let subdivisions: u32 = args.get(1).ok_or("missing subdivisions")?.parse()?;
        let out = args.get(2).ok_or("missing output path")?;
        let mesh = bumpy_sphere(subdivisions)?;
        write_mesh(out, &mesh)?;
        println!("wrote {out}: {} faces", mesh.face_count());
        return Ok(());
    }
    let input = args
        .first()
        .ok_or("usage: qem IN (--ratio R | --faces N) [--meshopt]")?;
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    let use_meshopt = args.iter().any(|a| a == "--meshopt");
    let mesh = read_mesh(input)?;
    let target = match (value("--ratio"), value("--faces")) {
        (Some(r), _) => (r.parse::<f64>()? * mesh.face_count() as f64).round() as usize,
        (None, Some(n)) => n.parse()?,
        (None, None) => return Err("missing --ratio R or --faces N".into()),
    };

    let start = Instant::now();
    let (out_vertices, out_triangles, method) = if use_meshopt {
        let indices: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
        let bytes = meshopt::typed_to_bytes(mesh.vertices());
        let adapter = meshopt::VertexDataAdapter::new(bytes, 12, 0)?;
        let result = meshopt::simplify(
            &indices,
            &adapter,
            target * 3,
            1.0,
            meshopt::SimplifyOptions::LockBorder,
            None,
        );
        let triangles = result
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect::<Vec<_>>();
        (mesh.vertices().to_vec(), triangles, "meshopt")
    } else {
        let out = decimate(
            &mesh,
            &DecimationOptions {
                target: Target::Faces(target),
                ..Default::default()
            },
        )?;
        let (v, t, ..) = out.mesh.into_parts();
        (v, t, "meshgnn")
    };
    let seconds = start.elapsed().as_secs_f64();
    if let Some(path) = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
    {
        write_mesh(
            path,
            &TriMesh::new(out_vertices.clone(), out_triangles.clone())?,
        )?;
    }
    if args.iter().any(|a| a == "--no-metrics") {
        println!(
            "{{\"method\": \"{method}\", \"input_faces\": {}, \"output_faces\": {}, \"seconds\": {seconds:.4}}}",
            mesh.face_count(),
            out_triangles.len()
        );
        return Ok(());
    }

    let area = |v: &[[f32; 3]], t: &[[u32; 3]]| -> f64 {
        t.iter()
            .map(|f| {
                let p = f.map(|i| v[i as usize].map(f64::from));
                let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
                let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
                let c = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
            })
            .sum()
    };
    let density: f64 = match args.iter().position(|a| a == "--density") {
        Some(i) => args.get(i + 1).ok_or("--density needs a value")?.parse()?,
        None => 4.0,
    };
    let h = (area(mesh.vertices(), mesh.triangles()) / (2e6 * density)).sqrt();
    let a = samples(mesh.vertices(), mesh.triangles(), h);
    let used: Vec<[f32; 3]> = {
        let mut seen = vec![false; out_vertices.len()];
        out_triangles
            .iter()
            .flatten()
            .for_each(|&i| seen[i as usize] = true);
        out_vertices
            .iter()
            .zip(&seen)
            .filter(|(_, s)| **s)
            .map(|(p, _)| *p)
            .collect()
    };
    let b = {
        let mut s = samples(&out_vertices, &out_triangles, h);
        s.drain(..out_vertices.len());
        s.extend(used);
        s
    };
    let (ab_max, ab_mean, ab_squared) = one_sided(&a, &b)?;
    let (ba_max, ba_mean, ba_squared) = one_sided(&b, &a)?;
    let diag = meshgnn_geometry::bounding_box_diagonal(mesh.vertices());
    println!(
        "{{\"method\": \"{method}\", \"input_faces\": {}, \"output_faces\": {}, \"seconds\": {seconds:.4}, \"hausdorff_rel\": {:.3e}, \"chamfer_rel\": {:.3e}, \"mean_squared_rel\": {:.3e}}}",
        mesh.face_count(),
        out_triangles.len(),
        ab_max.max(ba_max) / diag,
        (ab_mean + ba_mean) / diag,
        0.5 * (ab_squared + ba_squared) / (diag * diag),
    );
    Ok(())
}
