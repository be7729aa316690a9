//! Large meshes decimated as two spatial halves at once (beyond Garland & Heckbert 1997). The
//! collapse loop waits on memory, so a second core gains little inside one loop
//! (docs/qem.md), but it runs a second loop on another part of the mesh as fast as the first.
//!
//! The cut is the median vertex along the bounding box's longest axis. The faces with corners
//! on both sides (the seam) go into both halves with all their corners kept: each half then
//! sees every face around each vertex it may remove, its link and manifold checks see every
//! edge those collapses touch, and the seam comes out of both halves unchanged. The halves'
//! outputs are joined along it and decimated to the target as one mesh, which removes the
//! seam's vertices. That pass starts from the quadrics the halves summed (each vertex's from
//! the half of its side, the one that sees all its faces), so its costs are those the whole
//! mesh's loop would compute. An error bound (`max_error`) applies per pass, not to the sum of
//! what a vertex moved over the passes: such runs are decimated whole.

use std::borrow::Cow;
use std::collections::HashSet;
use std::sync::mpsc;

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use super::decimation::{Decimation, DecimationOptions, Target, decimate_whole};
use super::quadric::Quadric;
use crate::error::Result;

/// Meshes with fewer faces are decimated whole: below, the halves' threads, the join and the
/// last pass cost about what the second loop saves (even at 82k faces, 10 % kept; docs/qem.md).
const HALVES_MIN_FACES: usize = 100_000;

/// Targets keeping more than this share of the faces are decimated whole: the last pass,
/// over a joined mesh nearly as large as the input, costs more than the second loop saves
/// (at half the faces kept; a third still gains).
const HALVES_MAX_KEPT: f64 = 1.0 / 3.0;

/// Faces each half keeps beyond its share of the target and the seam, in seams: room for the
/// last pass to choose among, so the seam's collapses compete with the cheapest of the rest.
/// Without it, at 1 % of 1.3M faces (a 3k-face seam, 13k faces kept), the output's mean
/// squared distance to the input was 12 % above the whole loop's; with it, the same.
const JOIN_ROOM_SEAMS: usize = 1;

/// The share of the progress the two halves report; the pass over the joined mesh the rest.
const HALVES_PROGRESS: f64 = 0.9;

/// A face side: its three corners on side 0, on side 1, or on both (the seam).
const SEAM: u8 = 2;

/// One half: the faces of one side and the seam, over the vertices they use.
struct Half {
    mesh: TriMesh,
    /// Input vertex → index in `mesh`, `u32::MAX` outside the half.
    local: Vec<u32>,
    /// The seam's corners, as indices in `mesh`.
    keep: Vec<u32>,
}

/// A half decimated: where its vertices went, and the quadrics of those left.
struct DecimatedHalf {
    /// Input vertex → index in the half's input, `u32::MAX` outside the half.
    local: Vec<u32>,
    decimation: Decimation,
    quadrics: Vec<Quadric>,
}

impl DecimatedHalf {
    /// The output vertex of input vertex `v`, which the half holds.
    fn output_of(&self, v: usize) -> u32 {
        self.decimation.vertex_map[self.local[v] as usize]
    }
}

/// [`super::decimate`] of `mesh` as two spatial halves (on two threads when rayon's pool has
/// two), then the joined halves to `target` faces. `None` when the mesh has fewer than
/// [`HALVES_MIN_FACES`] faces, the target keeps more than [`HALVES_MAX_KEPT`] of them,
/// `options.max_error` is set, or a side of the cut holds no face: the caller decimates it
/// whole.
pub(super) fn decimate_in_halves(
    mesh: &TriMesh,
    options: &DecimationOptions,
    target: usize,
    progress: &mut dyn FnMut(f64),
) -> Option<Result<Decimation>> {
    let faces = mesh.face_count();
    if faces < HALVES_MIN_FACES
        || target as f64 > HALVES_MAX_KEPT * faces as f64
        || options.max_error.is_some()
    {
        return None;
    }
    let n = mesh.vertex_count();
    let side = vertex_sides(mesh);
    let face_side: Vec<u8> = mesh
        .triangles()
        .par_iter()
        .map(|t| {
            let s = t.map(|v| side[v as usize]);
            if s[0] == s[1] && s[1] == s[2] {
                s[0]
            } else {
                SEAM
            }
        })
        .collect();
    let mut side_faces = [0usize; 2];
    for &s in &face_side {
        if s != SEAM {
            side_faces[s as usize] += 1;
        }
    }
    if side_faces.contains(&0) {
        return None;
    }
    let mut on_seam = vec![false; n];
    for (t, _) in mesh
        .triangles()
        .iter()
        .zip(&face_side)
        .filter(|(_, s)| **s == SEAM)
    {
        for &v in t {
            on_seam[v as usize] = true;
        }
    }
    let seam_faces = face_side.len() - side_faces[0] - side_faces[1];
    // Each half keeps its share of the target, the seam and the join's room.
    let targets = [0, 1].map(|s| {
        let share = target as f64 * side_faces[s] as f64 / (side_faces[0] + side_faces[1]) as f64;
        share.round() as usize + (1 + JOIN_ROOM_SEAMS) * seam_faces
    });
    let split = Split {
        side,
        face_side,
        on_seam,
    };
    Some(decimate_halves(
        mesh, options, target, &split, targets, progress,
    ))
}

/// Where the cut runs through the faces.
struct Split {
    /// Per vertex: 0 below the cut, 1 at or above it.
    side: Vec<u8>,
    /// Per face: 0, 1 or [`SEAM`].
    face_side: Vec<u8>,
    /// Per vertex: a corner of a seam face.
    on_seam: Vec<bool>,
}

/// The side of the cut of every vertex: 1 at or above the median along the bounding box's
/// longest axis, 0 below.
fn vertex_sides(mesh: &TriMesh) -> Vec<u8> {
    let vertices = mesh.vertices();
    let extent = |k: usize| {
        let (lo, hi) = vertices
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
        hi - lo
    };
    let axis = (0..3)
        .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
        .unwrap_or(0);
    let mut coordinates: Vec<f32> = vertices.par_iter().map(|p| p[axis]).collect();
    let middle = coordinates.len() / 2;
    let (_, &mut median, _) = coordinates.select_nth_unstable_by(middle, f32::total_cmp);
    vertices
        .par_iter()
        .map(|p| u8::from(p[axis] >= median))
        .collect()
}

impl Split {
    /// The half of side `s`: its faces and the seam's, in input order, over the vertices they use
    /// (and this side's unused ones) in input order, with attributes.
    fn half(&self, mesh: &TriMesh, s: u8) -> Result<Half> {
        let Self {
            side,
            face_side,
            on_seam,
        } = self;
        let mut local = vec![u32::MAX; side.len()];
        let mut members = Vec::new();
        for (v, slot) in local.iter_mut().enumerate() {
            if side[v] == s || on_seam[v] {
                *slot = members.len() as u32;
                members.push(v);
            }
        }
        let subset = |values: &[[f32; 3]]| members.iter().map(|&v| values[v]).collect::<Vec<_>>();
        let faces: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .zip(face_side)
            .filter(|&(_, &fs)| fs == s || fs == SEAM)
            .map(|(t, _)| t.map(|v| local[v as usize]))
            .collect();
        let built = TriMesh::new(subset(mesh.vertices()), faces)
            .and_then(|m| match mesh.normals() {
                Some(normals) => m.with_normals(subset(normals)),
                None => Ok(m),
            })
            .and_then(|m| match mesh.uvs() {
                Some(uvs) => m.with_uvs(members.iter().map(|&v| uvs[v]).collect()),
                None => Ok(m),
            })
            .and_then(|m| match mesh.colors() {
                Some(colors) => m.with_colors(subset(colors)),
                None => Ok(m),
            })?;
        let kept = members
            .iter()
            .enumerate()
            .filter(|&(_, &v)| on_seam[v])
            .map(|(i, _)| i as u32)
            .collect();
        Ok(Half {
            mesh: built,
            local,
            keep: kept,
        })
    }
}

/// Decimates the two halves, joins them and decimates the joined mesh to `target`.
fn decimate_halves(
    mesh: &TriMesh,
    options: &DecimationOptions,
    target: usize,
    split: &Split,
    targets: [usize; 2],
    progress: &mut dyn FnMut(f64),
) -> Result<Decimation> {
    let [first, second] = decimate_both(mesh, options, split, targets, progress);
    let halves = [first?, second?];
    let joined = join(mesh, &halves, split)?;
    let [first, second] = halves.map(|h| h.decimation);
    let whole = DecimationOptions {
        target: Target::Faces(target),
        ..*options
    };
    let (last, _) = decimate_whole(
        Cow::Owned(joined.mesh),
        &whole,
        &[],
        Some(&joined.quadrics),
        &mut |f| progress(HALVES_PROGRESS + (1.0 - HALVES_PROGRESS) * f),
    )?;
    let error = first.error.max(second.error).max(last.error);
    Ok(Decimation {
        vertex_map: joined
            .vertex_map
            .iter()
            .map(|&j| last.vertex_map[j as usize])
            .collect(),
        error,
        error_distance: error.sqrt(),
        max_cost: first.max_cost.max(second.max_cost).max(last.max_cost),
        welded: first.welded || second.welded || last.welded,
        stop_reason: last.stop_reason,
        input_faces: mesh.face_count(),
        input_vertices: mesh.vertex_count(),
        collapses: first.collapses + second.collapses + last.collapses,
        mesh: last.mesh,
    })
}

/// Each half built and decimated to its target: on two threads, each with a one-thread pool
/// of its own, when rayon's pool has two or more, else one after the other. A half's mesh is
/// freed once its collapse loop holds the data. The halves' progress reaches `progress` on
/// this thread, through a channel.
fn decimate_both(
    mesh: &TriMesh,
    options: &DecimationOptions,
    split: &Split,
    targets: [usize; 2],
    progress: &mut dyn FnMut(f64),
) -> [Result<DecimatedHalf>; 2] {
    let run = |s: usize, report: &mut dyn FnMut(f64)| {
        let Half { mesh, local, keep } = split.half(mesh, s as u8)?;
        let half_options = DecimationOptions {
            target: Target::Faces(targets[s]),
            ..*options
        };
        let (decimation, quadrics) =
            decimate_whole(Cow::Owned(mesh), &half_options, &keep, None, report)?;
        Ok(DecimatedHalf {
            local,
            decimation,
            quadrics,
        })
    };
    if rayon::current_num_threads() < 2 {
        let mut done = 0.0;
        return [0, 1].map(|s| {
            let out = run(s, &mut |f| progress(HALVES_PROGRESS * (done + f) / 2.0));
            done = 1.0;
            out
        });
    }
    let (sender, receiver) = mpsc::channel::<(usize, f64)>();
    std::thread::scope(|scope| {
        let handles = [0, 1].map(|s| {
            let sender = sender.clone();
            let run = &run;
            scope.spawn(move || {
                let mut report = |f: f64| {
                    // The receiver lives until both halves are joined.
                    let _ = sender.send((s, f));
                };
                match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                    Ok(pool) => pool.install(|| run(s, &mut report)),
                    Err(_) => run(s, &mut report),
                }
            })
        });
        drop(sender);
        let mut done = [0.0; 2];
        for (i, f) in receiver {
            done[i] = f;
            progress(HALVES_PROGRESS * (done[0] + done[1]) / 2.0);
        }
        handles.map(|h| {
            h.join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    })
}

/// The two halves' outputs as one mesh, where each input vertex went in it, and the quadric
/// of each of its vertices.
struct Joined {
    mesh: TriMesh,
    vertex_map: Vec<u32>,
    quadrics: Vec<Quadric>,
}

/// Joins the halves' outputs: the first's vertices, then the second's that are no seam corner
/// (those the first holds too, unmoved), and the faces of both, the seam's once. A vertex's
/// quadric comes from the half of its side: a seam corner of the other side has only the
/// seam's faces in a half, and nothing collapses onto it there.
fn join(mesh: &TriMesh, halves: &[DecimatedHalf; 2], split: &Split) -> Result<Joined> {
    let Split {
        side,
        face_side,
        on_seam,
    } = split;
    let [first, second] = halves.each_ref().map(|h| &h.decimation);
    let (first_quadrics, second_quadrics) = (&halves[0].quadrics, &halves[1].quadrics);
    let through = |h: usize, v: usize| halves[h].output_of(v);
    // The second output's vertices in the joined numbering: a seam corner's is the first's.
    let first_count = first.mesh.vertex_count() as u32;
    let mut second_index = vec![u32::MAX; second.mesh.vertex_count()];
    let mut quadrics = first_quadrics.clone();
    for v in (0..on_seam.len()).filter(|&v| on_seam[v]) {
        second_index[through(1, v) as usize] = through(0, v);
        if side[v] == 1 {
            quadrics[through(0, v) as usize] = second_quadrics[through(1, v) as usize];
        }
    }
    let mut extra = Vec::new();
    for (o, slot) in second_index.iter_mut().enumerate() {
        if *slot == u32::MAX {
            *slot = first_count + extra.len() as u32;
            extra.push(o);
            quadrics.push(second_quadrics[o]);
        }
    }
    let seam: HashSet<[u32; 3]> = mesh
        .triangles()
        .iter()
        .zip(face_side)
        .filter(|&(_, &s)| s == SEAM)
        .map(|(t, _)| sorted(t.map(|v| through(0, v as usize))))
        .collect();
    let mut faces = first.mesh.triangles().to_vec();
    faces.extend(
        second
            .mesh
            .triangles()
            .iter()
            .map(|t| t.map(|o| second_index[o as usize]))
            .filter(|t| !(t.iter().all(|&j| j < first_count) && seam.contains(&sorted(*t)))),
    );
    let appended = |values: &[[f32; 3]], more: &[[f32; 3]]| -> Vec<[f32; 3]> {
        values
            .iter()
            .copied()
            .chain(extra.iter().map(|&o| more[o]))
            .collect()
    };
    let mut joined = TriMesh::new(
        appended(first.mesh.vertices(), second.mesh.vertices()),
        faces,
    )?;
    if let (Some(a), Some(b)) = (first.mesh.normals(), second.mesh.normals()) {
        joined = joined.with_normals(appended(a, b))?;
    }
    if let (Some(a), Some(b)) = (first.mesh.uvs(), second.mesh.uvs()) {
        joined = joined.with_uvs(
            a.iter()
                .copied()
                .chain(extra.iter().map(|&o| b[o]))
                .collect(),
        )?;
    }
    if let (Some(a), Some(b)) = (first.mesh.colors(), second.mesh.colors()) {
        joined = joined.with_colors(appended(a, b))?;
    }
    let vertex_map = (0..on_seam.len())
        .map(|v| match halves[0].local[v] {
            u32::MAX => second_index[through(1, v) as usize],
            _ => through(0, v),
        })
        .collect();
    Ok(Joined {
        mesh: joined,
        vertex_map,
        quadrics,
    })
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use meshgnn_geometry::{grid_plane, subdivided_cube};

    use super::*;
    use crate::qem::decimation::decimate;

    /// A closed bumpy ball of 101 568 faces: a subdivided cube pushed onto a sphere with
    /// bumps, so the quadrics differ from place to place.
    fn bumpy_ball() -> TriMesh {
        let cube = subdivided_cube(92);
        let vertices = cube
            .vertices()
            .iter()
            .map(|p| {
                let r = p.iter().map(|x| x * x).sum::<f32>().sqrt();
                let bump =
                    1.0 + 0.05 * (5.0 * p[0]).sin() * (5.0 * p[1]).sin() * (5.0 * p[2]).sin();
                p.map(|x| x / r * bump)
            })
            .collect();
        cube.with_vertices(vertices).unwrap()
    }

    fn options(target: usize) -> DecimationOptions {
        DecimationOptions {
            target: Target::Faces(target),
            ..Default::default()
        }
    }

    /// Undirected edge → face count, and whether a directed edge repeats (a flipped face).
    fn edge_counts(mesh: &TriMesh) -> (HashMap<[u32; 2], usize>, bool) {
        let mut undirected = HashMap::new();
        let mut directed = HashMap::new();
        for t in mesh.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *undirected.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
                *directed.entry([a, b]).or_insert(0) += 1;
            }
        }
        let repeated = directed.values().any(|&c| c > 1);
        (undirected, repeated)
    }

    #[test]
    fn halves_give_a_closed_ball_as_good_as_the_whole_loop() {
        let ball = bumpy_ball();
        assert!(ball.face_count() >= HALVES_MIN_FACES);
        for target in [10_000, 1_000] {
            let halves = decimate_in_halves(&ball, &options(target), target, &mut |_| {})
                .expect("large enough to split")
                .unwrap();
            let (whole, _) = decimate_whole(
                Cow::Borrowed(&ball),
                &options(target),
                &[],
                None,
                &mut |_| {},
            )
            .unwrap();
            assert_eq!(halves.mesh.face_count(), whole.mesh.face_count());
            let (edges, flipped) = edge_counts(&halves.mesh);
            assert!(
                edges.values().all(|&c| c == 2) && !flipped,
                "target {target}"
            );
            // Euler characteristic of a sphere.
            let v = halves.mesh.vertex_count() as i64;
            assert_eq!(v - edges.len() as i64 + halves.mesh.face_count() as i64, 2);
            // The quadric error of the worst collapse, against the whole loop's.
            assert!(
                halves.error <= 1.5 * whole.error,
                "target {target}: {} against {}",
                halves.error,
                whole.error
            );
            assert_eq!(halves.vertex_map.len(), ball.vertex_count());
            assert!(halves.vertex_map.iter().all(|&o| (o as usize) < v as usize));
        }
    }

    #[test]
    fn a_triangle_soup_is_welded_across_the_cut() {
        // Every face with vertices of its own: the copies of a position on the seam must land
        // on the one kept vertex in each half, or the halves would tear apart.
        let ball = bumpy_ball();
        let vertices = (0..ball.face_count())
            .flat_map(|f| ball.triangle_positions(f))
            .collect();
        let triangles = (0..ball.face_count() as u32)
            .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
            .collect();
        let soup = TriMesh::new(vertices, triangles).unwrap();
        let out = decimate_in_halves(&soup, &options(2_000), 2_000, &mut |_| {})
            .expect("large enough to split")
            .unwrap();
        assert!(out.welded);
        assert_eq!(out.mesh.face_count(), 2_000);
        let (edges, flipped) = edge_counts(&out.mesh);
        assert!(edges.values().all(|&c| c == 2) && !flipped);
        let v = out.mesh.vertex_count() as i64;
        assert_eq!(v - edges.len() as i64 + 2_000, 2);
    }

    #[test]
    fn halves_give_the_same_output_for_one_and_two_threads() {
        let ball = bumpy_ball();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| decimate(&ball, &options(5_000)).unwrap())
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn halves_keep_an_open_border() {
        // 105 800 faces: the border vertices stay on the square's border through both halves
        // and the last pass (attributes through the halves: tests/qem_decimation.rs).
        let grid = grid_plane(230, 230);
        let out = decimate_in_halves(&grid, &options(2_000), 2_000, &mut |_| {})
            .expect("large enough to split")
            .unwrap();
        assert!(out.mesh.face_count() <= 2_000);
        let (edges, flipped) = edge_counts(&out.mesh);
        assert!(edges.values().all(|&c| c <= 2) && !flipped);
        let on_square_border = |p: [f32; 3]| p[0].min(p[1]) < 1e-6 || p[0].max(p[1]) > 1.0 - 1e-6;
        let border: Vec<_> = edges
            .iter()
            .filter(|&(_, &c)| c == 1)
            .map(|(e, _)| e)
            .collect();
        assert!(!border.is_empty());
        for e in border {
            let [a, b] = e.map(|v| out.mesh.vertices()[v as usize]);
            assert!(
                on_square_border(a) && on_square_border(b),
                "{a:?} {b:?} off the border"
            );
        }
    }

    #[test]
    fn small_meshes_light_targets_and_error_bounds_are_decimated_whole() {
        let ball = bumpy_ball();
        let faces = ball.face_count();
        let grid = grid_plane(100, 100); // 20 000 faces
        assert!(decimate_in_halves(&grid, &options(2_000), 2_000, &mut |_| {}).is_none());
        assert!(decimate_in_halves(&ball, &options(faces / 2), faces / 2, &mut |_| {}).is_none());
        let bounded = DecimationOptions {
            max_error: Some(0.01),
            ..options(1_000)
        };
        assert!(decimate_in_halves(&ball, &bounded, 1_000, &mut |_| {}).is_none());
    }
}
