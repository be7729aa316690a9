//! Known-answer and invariant tests of QEM decimation.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::HashMap;

use meshgnn_geometry::{TriMesh, grid_plane, icosphere, subdivided_cube, torus};
use meshgnn_graph::{
    Decimation, DecimationOptions, Error, StopReason, Target, decimate, decimate_keeping,
};

fn options(target: Target) -> DecimationOptions {
    DecimationOptions {
        target,
        ..Default::default()
    }
}

/// An icosphere with deterministic radial noise of relative amplitude `amp`.
fn noisy_sphere(subdivisions: u32, amp: f32) -> TriMesh {
    let sphere = icosphere(subdivisions);
    let vertices = sphere
        .vertices()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let h = ((i as f32 * 12.9898).sin() * 43758.547).fract();
            p.map(|x| x * (1.0 + amp * h))
        })
        .collect();
    sphere.with_vertices(vertices).unwrap()
}

/// (boundary edges, non-manifold edges, directed edges used twice: inconsistent orientation).
fn edge_defects(mesh: &TriMesh) -> (usize, usize, usize) {
    let mut undirected: HashMap<(u32, u32), usize> = HashMap::new();
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *undirected.entry((a.min(b), a.max(b))).or_default() += 1;
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    let boundary = undirected.values().filter(|&&c| c == 1).count();
    let non_manifold = undirected.values().filter(|&&c| c > 2).count();
    let misoriented = directed.values().filter(|&&c| c > 1).count();
    (boundary, non_manifold, misoriented)
}

fn assert_closed_manifold(mesh: &TriMesh) {
    let (boundary, non_manifold, misoriented) = edge_defects(mesh);
    assert_eq!((boundary, non_manifold, misoriented), (0, 0, 0));
    let edges = 3 * mesh.face_count() / 2;
    let used = {
        let mut seen = vec![false; mesh.vertex_count()];
        mesh.triangles()
            .iter()
            .flatten()
            .for_each(|&v| seen[v as usize] = true);
        seen.iter().filter(|&&s| s).count()
    };
    // Euler characteristic of a sphere.
    assert_eq!(used as i64 - edges as i64 + mesh.face_count() as i64, 2);
}

#[test]
fn cube_collapses_to_its_twelve_corner_triangles() {
    let out = decimate(&subdivided_cube(8), &options(Target::Faces(12))).unwrap();
    assert_eq!(out.mesh.face_count(), 12);
    assert_eq!(out.mesh.vertex_count(), 8);
    assert!(out.error_distance < 1e-5, "{}", out.error_distance);
    assert_eq!(out.stop_reason, StopReason::TargetReached);
    let mut corners: Vec<[i32; 3]> = out
        .mesh
        .vertices()
        .iter()
        .map(|p| {
            for x in p {
                assert!((x.abs() - 1.0).abs() < 1e-5, "{p:?} is not a corner");
            }
            p.map(|x| x.signum() as i32)
        })
        .collect();
    corners.sort();
    corners.dedup();
    assert_eq!(corners.len(), 8);
    assert_closed_manifold(&out.mesh);
}

#[test]
fn grid_collapses_to_two_triangles_on_its_corners() {
    let out = decimate(&grid_plane(16, 16), &options(Target::Faces(2))).unwrap();
    assert_eq!(out.mesh.face_count(), 2);
    let mut corners: Vec<[u32; 3]> = out
        .mesh
        .vertices()
        .iter()
        .map(|p| p.map(|x| (x * 1e4).round() as u32))
        .collect();
    corners.sort();
    assert_eq!(
        corners,
        vec![[0, 0, 0], [0, 10000, 0], [10000, 0, 0], [10000, 10000, 0]]
    );
}

#[test]
fn open_disk_keeps_its_boundary() {
    let grid = grid_plane(24, 24);
    let bumped = grid
        .vertices()
        .iter()
        .map(|p| {
            let z = 0.2 * (std::f32::consts::PI * p[0]).sin() * (std::f32::consts::PI * p[1]).sin();
            [p[0], p[1], z]
        })
        .collect();
    let mesh = grid.with_vertices(bumped).unwrap();
    let out = decimate(&mesh, &options(Target::Ratio(0.1))).unwrap();
    let (boundary, non_manifold, misoriented) = edge_defects(&out.mesh);
    assert_eq!((non_manifold, misoriented), (0, 0));
    assert!(boundary >= 4);
    // Every boundary edge lies on the unit square's perimeter; together they span it.
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for t in out.mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let v = out.mesh.vertices();
    let on_side = |p: [f32; 3]| {
        p.iter()
            .take(2)
            .any(|x| x.abs() < 1e-5 || (x - 1.0).abs() < 1e-5)
            && p[2].abs() < 1e-5
    };
    let mut perimeter = 0.0f64;
    for (&(a, b), _) in count.iter().filter(|(_, c)| **c == 1) {
        let (pa, pb) = (v[a as usize], v[b as usize]);
        assert!(on_side(pa) && on_side(pb), "{pa:?} {pb:?}");
        perimeter += (0..3)
            .map(|i| f64::from(pa[i] - pb[i]).powi(2))
            .sum::<f64>()
            .sqrt();
    }
    assert!((perimeter - 4.0).abs() < 1e-4, "{perimeter}");
}

/// The smallest cosine between a face normal and the radial direction through its centroid.
fn min_radial_cosine(mesh: &TriMesh) -> f64 {
    mesh.triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices()[i as usize].map(f64::from));
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let m = [0, 1, 2].map(|i| a[i] + b[i] + c[i]);
            let dot = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
            let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            dot / (len(n) * len(m))
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn noisy_sphere_never_flips_and_stays_watertight() {
    // Radial noise of 1% (15% of an edge): every face must still point outwards. At 5%
    // (75% of an edge) input faces are already tilted by up to 58°; the radial check there is
    // `noisy_sphere_with_outward_input_stays_outward`.
    for (amp, ratios) in [(0.01, [0.2, 0.05, 0.01]), (0.05, [0.5, 0.2, 0.05])] {
        let mesh = noisy_sphere(4, amp);
        for ratio in ratios {
            let out = decimate(&mesh, &options(Target::Ratio(ratio))).unwrap();
            let target = (ratio * mesh.face_count() as f64).round();
            assert!((out.mesh.face_count() as f64 - target).abs() <= 0.01 * target + 1.0);
            if amp <= 0.01 {
                let cos = min_radial_cosine(&out.mesh);
                assert!(cos > 0.0, "ratio {ratio}: a face points inwards ({cos})");
            }
            assert_closed_manifold(&out.mesh);
            assert_eq!(out.vertex_map.len(), mesh.vertex_count());
            assert!(
                out.vertex_map
                    .iter()
                    .all(|&m| (m as usize) < out.mesh.vertex_count())
            );
        }
    }
}

#[test]
fn noisy_sphere_with_outward_input_stays_outward() {
    // Regression: at 5% radial noise and a 50% target one face came out tilted inwards
    // (radial cosine -0.009) although the input has none: the check against the single
    // input face a face descends from allowed it to stand ~70° off that face and past 90° off
    // the surface. Moved faces are now checked against the input surface their corners
    // represent (the sum of their region normals).
    for subdivisions in [4, 5] {
        for amp in [0.01, 0.02, 0.05] {
            let mesh = noisy_sphere(subdivisions, amp);
            // The reference is valid: every input face points outwards.
            assert!(min_radial_cosine(&mesh) > 0.0);
            for ratio in [0.5, 0.2, 0.05] {
                let out = decimate(&mesh, &options(Target::Ratio(ratio))).unwrap();
                assert_eq!(out.stop_reason, StopReason::TargetReached);
                let cos = min_radial_cosine(&out.mesh);
                assert!(
                    cos > 0.0,
                    "subdivisions {subdivisions}, noise {amp}, ratio {ratio}: a face points \
                     inwards ({cos})"
                );
                assert_closed_manifold(&out.mesh);
            }
        }
    }
}

#[test]
fn folded_input_faces_do_not_freeze_their_neighbourhood() {
    // Scans hold small faces folded over against their neighbours (2 % of snowden.obj's
    // faces point away from their corners' region normals). Here every seventh vertex is
    // pushed past one of its neighbours, which folds the faces on that edge over. A check
    // that refused every collapse leaving such a face folded stopped these short of the target.
    let sphere = icosphere(4);
    let mut vertices = sphere.vertices().to_vec();
    let mut neighbour = vec![u32::MAX; vertices.len()];
    for t in sphere.triangles() {
        for k in 0..3 {
            neighbour[t[k] as usize] = t[(k + 1) % 3];
        }
    }
    for v in (0..vertices.len()).step_by(7) {
        let (p, q) = (vertices[v], vertices[neighbour[v] as usize]);
        vertices[v] = std::array::from_fn(|k| q[k] + 0.3 * (q[k] - p[k]));
    }
    let folded = sphere.with_vertices(vertices).unwrap();
    for ratio in [0.2, 0.05] {
        let out = decimate(&folded, &options(Target::Ratio(ratio))).unwrap();
        let target = (ratio * folded.face_count() as f64).round();
        assert_eq!(out.stop_reason, StopReason::TargetReached, "ratio {ratio}");
        assert!((out.mesh.face_count() as f64 - target).abs() <= 0.01 * target + 1.0);
        assert_closed_manifold(&out.mesh);
    }
}

/// Decimates `mesh` to 1 % and checks that it gets there and stays closed.
fn thin_part_reaches_one_percent(name: &str, mesh: &TriMesh) -> Decimation {
    let out = decimate(mesh, &options(Target::Ratio(0.01))).unwrap();
    let target = (0.01 * mesh.face_count() as f64).round();
    assert!(
        out.mesh.face_count() as f64 <= 1.01 * target,
        "{name}: {} faces for {target} ({:?})",
        out.mesh.face_count(),
        out.stop_reason
    );
    let (boundary, non_manifold, misoriented) = edge_defects(&out.mesh);
    assert_eq!((boundary, non_manifold, misoriented), (0, 0, 0), "{name}");
    out
}

#[test]
fn a_thin_plate_reaches_one_percent() {
    // A 2 × 2 × 0.005 box: at 1 % its rim's faces stand edge-on to their corners' surface (the
    // top or the bottom), and moving them was refused (stopped at 148 faces for 31).
    let cube = subdivided_cube(16);
    let flattened = cube
        .vertices()
        .iter()
        .map(|&[x, y, z]| [x, y, 0.0025 * z])
        .collect();
    let plate = cube.with_vertices(flattened).unwrap();
    let out = thin_part_reaches_one_percent("plate", &plate);
    for p in out.mesh.vertices() {
        assert!(p[0].abs() <= 1.0 + 1e-4 && p[1].abs() <= 1.0 + 1e-4 && p[2].abs() <= 0.0026);
    }
}

#[test]
fn a_thin_noisy_ring_reaches_one_percent() {
    // A wire ring (tube radius 1 % of the ring's) with noise of a fifth of the tube radius: at
    // 1 % the corners of a face stand for opposite sides of the tube, their summed normals
    // point anywhere, and a check against it stopped at 98 faces for 82.
    let ring = torus(1.0, 0.02, 256, 16);
    let noisy = ring
        .vertices()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let h = |k: f32| ((i as f32 * 12.9898 + k * 78.233).sin() * 43758.547).fract() - 0.5;
            [
                p[0] + 0.008 * h(0.0),
                p[1] + 0.008 * h(1.0),
                p[2] + 0.008 * h(2.0),
            ]
        })
        .collect();
    let out = thin_part_reaches_one_percent("ring", &ring.with_vertices(noisy).unwrap());
    for p in out.mesh.vertices() {
        let around = (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!(((around - 1.0).powi(2) + p[2] * p[2]).sqrt() < 0.1, "{p:?}");
    }
}

#[test]
fn face_count_within_one_percent_of_target() {
    let mesh = noisy_sphere(5, 0.01);
    let out = decimate(&mesh, &options(Target::Faces(2000))).unwrap();
    assert!(out.mesh.face_count().abs_diff(2000) <= 20);
    assert!(out.mesh.face_count() <= 2000);
    assert_eq!(out.input_faces, 20480);
}

#[test]
fn same_output_for_one_and_two_threads() {
    let mesh = noisy_sphere(4, 0.05);
    let run = |threads: usize| -> Decimation {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| decimate(&mesh, &options(Target::Ratio(0.1))).unwrap())
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn triangle_soup_is_welded() {
    let sphere = icosphere(2);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for f in 0..sphere.face_count() {
        let base = vertices.len() as u32;
        vertices.extend(sphere.triangle_positions(f));
        triangles.push([base, base + 1, base + 2]);
    }
    let soup = TriMesh::new(vertices, triangles).unwrap();
    let out = decimate(&soup, &options(Target::Ratio(0.5))).unwrap();
    assert!(out.welded);
    assert_eq!(out.mesh.face_count(), 160);
    assert_closed_manifold(&out.mesh);
    assert_eq!(out.vertex_map.len(), 3 * 320);
    // Copies of one position land on one output vertex.
    let twin = (1..soup.vertex_count())
        .find(|&i| soup.vertices()[i] == soup.vertices()[0])
        .unwrap();
    assert_eq!(out.vertex_map[0], out.vertex_map[twin]);

    let plain = decimate(&sphere, &options(Target::Ratio(0.5))).unwrap();
    assert!(!plain.welded);
}

#[test]
fn attributes_are_carried_through_collapses() {
    // The second grid (105 800 faces) is decimated as blocks joined after.
    for (cells, ratio) in [(12, 0.1), (230, 0.02)] {
        attributes_are_carried_through_collapses_of(grid_plane(cells, cells), ratio);
    }
}

fn attributes_are_carried_through_collapses_of(grid: TriMesh, ratio: f64) {
    let uvs: Vec<[f32; 2]> = grid.vertices().iter().map(|p| [p[0], p[1]]).collect();
    let colors: Vec<[f32; 3]> = grid.vertices().iter().map(|p| [p[0], p[1], 0.5]).collect();
    let normals = vec![[0.0, 0.0, 1.0]; grid.vertex_count()];
    let mesh = grid
        .with_uvs(uvs)
        .unwrap()
        .with_colors(colors)
        .unwrap()
        .with_normals(normals)
        .unwrap();
    let out = decimate(&mesh, &options(Target::Ratio(ratio))).unwrap();
    assert!(out.mesh.face_count() as f64 <= (ratio * mesh.face_count() as f64).ceil());
    let (v, uv, col, nor) = (
        out.mesh.vertices(),
        out.mesh.uvs().unwrap(),
        out.mesh.colors().unwrap(),
        out.mesh.normals().unwrap(),
    );
    for i in 0..v.len() {
        // The attributes are linear in position, so interpolation reproduces them.
        assert!((uv[i][0] - v[i][0]).abs() < 1e-5 && (uv[i][1] - v[i][1]).abs() < 1e-5);
        assert!((col[i][0] - v[i][0]).abs() < 1e-5 && (col[i][2] - 0.5).abs() < 1e-6);
        assert!((nor[i][2] - 1.0).abs() < 1e-6);
    }
}

#[test]
fn uv_seams_collapse_with_their_twins_and_never_tear() {
    // A bumped grid cut into three UV islands sharing positions along the seams: x < 0.5,
    // and the right half split at y = 0.5 (three islands meet at (0.5, 0.5)).
    let grid = grid_plane(8, 8);
    let mut vertices: Vec<[f32; 3]> = grid
        .vertices()
        .iter()
        .map(|p| [p[0], p[1], 0.1 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos()])
        .collect();
    let mut uvs: Vec<[f32; 2]> = vertices.iter().map(|p| [p[0], p[1]]).collect();
    let island_of = |t: &[u32; 3]| {
        let centre = |k: usize| {
            t.iter()
                .map(|&v| grid.vertices()[v as usize][k])
                .sum::<f32>()
                / 3.0
        };
        match (centre(0) > 0.5, centre(1) > 0.5) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        }
    };
    // A vertex keeps its index in the first island that uses it; the others get a copy.
    let mut first_island = vec![usize::MAX; vertices.len()];
    for t in grid.triangles() {
        let island = island_of(t);
        for &v in t {
            first_island[v as usize] = first_island[v as usize].min(island);
        }
    }
    let mut copy = HashMap::new();
    let triangles = grid
        .triangles()
        .iter()
        .map(|t| {
            let island = island_of(t);
            t.map(|v| {
                if first_island[v as usize] == island {
                    return v;
                }
                let p = vertices[v as usize];
                *copy.entry((v, island)).or_insert_with(|| {
                    vertices.push(p);
                    uvs.push([p[0] + 0.25 * island as f32, p[1]]);
                    vertices.len() as u32 - 1
                })
            })
        })
        .collect();
    let mesh = TriMesh::new(vertices, triangles)
        .unwrap()
        .with_uvs(uvs)
        .unwrap();
    // With their seam vertices fixed, the islands keep at least 8 + 4 + 4 triangles on the
    // seams; the vertex where all three meet stays.
    let out = decimate(&mesh, &options(Target::Faces(8))).unwrap();
    assert_eq!(out.stop_reason, StopReason::TargetReached);
    assert!(out.mesh.face_count() <= 8);
    // No tear: welded by position, the output has border edges only on the square's
    // perimeter, and no edge has more than two faces.
    let v = out.mesh.vertices();
    let key = |p: [f32; 3]| p.map(f32::to_bits);
    let mut faces_per_edge: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
    for t in out.mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (key(v[t[k] as usize]), key(v[t[(k + 1) % 3] as usize]));
            *faces_per_edge.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let on_perimeter = |p: [u32; 3]| {
        let [x, y, _] = p.map(f32::from_bits);
        x.min(y) < 1e-4 || x.max(y) > 1.0 - 1e-4
    };
    for ((a, b), count) in faces_per_edge {
        assert!(count <= 2);
        if count == 1 {
            assert!(on_perimeter(a) && on_perimeter(b), "torn at {a:?}-{b:?}");
        }
    }
}

/// Three bumped 16 × 16 pages bound along a spine on the z axis (each spine edge has three
/// faces), the first page listed twice, the copy with the opposite orientation (as scans hold
/// doubled sheets).
fn book_of_three_pages() -> TriMesh {
    let grid = grid_plane(16, 16);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for page in 0..3 {
        let angle = page as f32 * std::f32::consts::TAU / 3.0;
        let (sin, cos) = angle.sin_cos();
        let offset = vertices.len() as u32;
        vertices.extend(grid.vertices().iter().map(|&[u, v, _]| {
            if u == 0.0 {
                return [0.0, 0.0, v];
            }
            let bump = 0.05 * (std::f32::consts::PI * u).sin() * (std::f32::consts::PI * v).sin();
            [u * cos - bump * sin, u * sin + bump * cos, v]
        }));
        triangles.extend(grid.triangles().iter().map(|t| t.map(|v| v + offset)));
    }
    let first_page = grid.triangles().len();
    triangles.extend_from_within(..first_page);
    for t in &mut triangles[3 * first_page..] {
        t.swap(1, 2);
    }
    TriMesh::new(vertices, triangles).unwrap()
}

#[test]
fn non_manifold_spine_collapses_along_itself_and_never_gets_worse() {
    let mesh = book_of_three_pages();
    assert_eq!(mesh.face_count(), 4 * 512);
    // Each page keeps at least the triangles from its spine vertices to its far side: 16 per
    // page while the 17 spine vertices stay, so 30 faces need collapses along the spine.
    let out = decimate(&mesh, &options(Target::Faces(30))).unwrap();
    assert_eq!(out.stop_reason, StopReason::TargetReached);
    assert!(out.mesh.face_count() <= 30, "{}", out.mesh.face_count());
    let mut faces_per_edge: HashMap<(u32, u32), usize> = HashMap::new();
    let mut distinct = std::collections::HashSet::new();
    for t in out.mesh.triangles() {
        let mut key = *t;
        key.sort_unstable();
        assert!(distinct.insert(key), "duplicate face {t:?}");
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *faces_per_edge.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    // The pages stay bound: the spine still has edges with three faces, none has more, and
    // every such edge lies on the spine.
    let v = out.mesh.vertices();
    let spine: Vec<_> = faces_per_edge.iter().filter(|(_, c)| **c > 2).collect();
    assert!(!spine.is_empty());
    for (&(a, b), &count) in spine {
        assert_eq!(count, 3, "edge ({a}, {b}) has {count} faces");
        for p in [v[a as usize], v[b as usize]] {
            assert!(
                p[0].abs() < 1e-6 && p[1].abs() < 1e-6,
                "{p:?} left the spine"
            );
        }
    }
}

/// A unit icosphere with a fin on every 9th face: a triangle on one of the face's edges out to
/// a new vertex just above it (each such edge gets three faces, the fin's other two edges one),
/// as scans hold flaps on their surface.
fn sphere_with_fins() -> TriMesh {
    let sphere = icosphere(4);
    let mut vertices = sphere.vertices().to_vec();
    let mut triangles = sphere.triangles().to_vec();
    for t in sphere.triangles().iter().step_by(9) {
        let [a, b, c] = t.map(|v| sphere.vertices()[v as usize]);
        let tip: [f32; 3] = std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0 * 1.01);
        vertices.push(tip);
        triangles.push([t[0], t[1], vertices.len() as u32 - 1]);
    }
    TriMesh::new(vertices, triangles).unwrap()
}

#[test]
fn fins_once_folded_in_free_their_vertices() {
    let mesh = sphere_with_fins();
    let (boundary, non_manifold, _) = edge_defects(&mesh);
    assert_eq!((boundary, non_manifold), (2 * 569, 569));
    // Collapsing a fin's tip into its edge leaves that edge with two faces: its ends are then
    // ordinary vertices, free to go (stale flags pinned them: 1 % stopped at 2 190 faces).
    let out = decimate(&mesh, &options(Target::Ratio(0.01))).unwrap();
    assert_eq!(
        out.stop_reason,
        StopReason::TargetReached,
        "{}",
        out.mesh.face_count()
    );
    assert_closed_manifold(&out.mesh);
    // Still a sphere: the fins' border planes stay in the quadrics of their edges' ends and
    // pull them (a quarter of the radius at worst at 1 %; 0.08 without fins).
    let worst = out
        .mesh
        .vertices()
        .iter()
        .map(|p| (p.iter().map(|x| x * x).sum::<f32>().sqrt() - 1.0).abs())
        .fold(0.0, f32::max);
    assert!(worst < 0.25, "{worst}");
}

#[test]
fn keep_original_positions_places_vertices_on_inputs() {
    let mesh = noisy_sphere(3, 0.05);
    let out = decimate(
        &mesh,
        &DecimationOptions {
            target: Target::Ratio(0.25),
            keep_original_positions: true,
            ..Default::default()
        },
    )
    .unwrap();
    for (j, p) in out.mesh.vertices().iter().enumerate() {
        let source = mesh.vertices().iter().position(|q| q == p).unwrap();
        assert_eq!(out.vertex_map[source] as usize, j);
    }
    assert_closed_manifold(&out.mesh);
}

/// Every vertex of `keep` is an output vertex of its own, at its input position.
fn assert_kept_in_place(mesh: &TriMesh, out: &Decimation, keep: &[u32]) {
    let mut outputs: Vec<u32> = keep.iter().map(|&v| out.vertex_map[v as usize]).collect();
    for (&v, &o) in keep.iter().zip(&outputs) {
        assert_eq!(out.mesh.vertices()[o as usize], mesh.vertices()[v as usize]);
    }
    outputs.sort_unstable();
    outputs.dedup();
    assert_eq!(
        outputs.len(),
        keep.len(),
        "a kept vertex was removed or merged"
    );
}

#[test]
fn kept_vertices_survive_in_place_and_the_rest_collapses_onto_them() {
    let mesh = noisy_sphere(3, 0.05); // 642 vertices
    let keep: Vec<u32> = (0..642).filter(|v| v % 7 == 3).collect();
    // As far as possible, every vertex at an input position.
    let collapse_all = DecimationOptions {
        target: Target::Faces(1),
        keep_original_positions: true,
        ..Default::default()
    };
    let out = decimate_keeping(&mesh, &collapse_all, &keep, &mut |_| {}).unwrap();
    assert_kept_in_place(&mesh, &out, &keep);
    // Nearly every other vertex goes (a few are held by the manifold and flip checks).
    let others = out.mesh.vertex_count() - keep.len();
    assert!(
        others * 20 < keep.len(),
        "{others} others left of {}",
        642 - keep.len()
    );
    assert_eq!(out.stop_reason, StopReason::NoValidCollapse);
    assert_closed_manifold(&out.mesh);
    // Without the kept list the same target goes further, through the kept vertices.
    let free = decimate(&mesh, &collapse_all).unwrap();
    assert!(free.mesh.vertex_count() < keep.len());
    assert!(decimate_keeping(&mesh, &options(Target::Ratio(0.5)), &[642], &mut |_| {}).is_err());
}

#[test]
fn kept_vertices_beside_a_border_or_a_non_manifold_edge_stay() {
    // A kept interior vertex next to a border vertex: the border rule (an interior vertex
    // collapses onto the border) must not remove it; the edge between them stays instead.
    let grid = grid_plane(8, 8); // 81 vertices, row-major, 9 per row
    let ring: Vec<u32> = (1..8)
        .flat_map(|j| [9 * j + 1, 9 * j + 7])
        .chain((2..7).flat_map(|i| [9 + i, 63 + i]))
        .collect();
    // The same beside the spine of a book of three pages (vertices on a non-manifold edge).
    let book = book_of_three_pages();
    let spine_neighbours: Vec<u32> = (0..book.vertex_count() as u32)
        .filter(|&v| {
            let p = book.vertices()[v as usize];
            p[0] != 0.0 || p[1] != 0.0
        })
        .collect();
    for (mesh, keep) in [(grid, ring), (book, spine_neighbours)] {
        let collapse_all = DecimationOptions {
            target: Target::Faces(1),
            ..Default::default()
        };
        let out = decimate_keeping(&mesh, &collapse_all, &keep, &mut |_| {}).unwrap();
        assert_kept_in_place(&mesh, &out, &keep);
    }
}

#[test]
fn max_error_stops_early_and_bounds_the_error() {
    let mesh = noisy_sphere(4, 0.05);
    let out = decimate(
        &mesh,
        &DecimationOptions {
            target: Target::Faces(10),
            max_error: Some(0.01),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(out.stop_reason, StopReason::MaxError);
    assert!(out.error_distance <= 0.01);
    assert!(out.mesh.face_count() > 10 && out.mesh.face_count() < mesh.face_count());
}

#[test]
fn rejects_bad_ratio_and_empty_mesh() {
    let mesh = icosphere(1);
    for r in [0.0, -0.5, 1.5, f64::NAN] {
        assert!(matches!(
            decimate(&mesh, &options(Target::Ratio(r))),
            Err(Error::InvalidParameter { name: "ratio", .. })
        ));
    }
    let empty = TriMesh::new(vec![[0.0; 3]], vec![]).unwrap();
    assert!(matches!(
        decimate(&empty, &DecimationOptions::default()),
        Err(Error::Empty { .. })
    ));
    let out = decimate(&mesh, &options(Target::Ratio(1.0))).unwrap();
    assert_eq!(out.mesh.face_count(), mesh.face_count());
}
