//! Large meshes decimated as spatial blocks, taken by the threads as they free up (beyond
//! Garland & Heckbert 1997). The collapse loop waits on memory, so a second core gains little
//! inside one loop (docs/qem.md), but it runs a second loop on another part of the mesh as
//! fast as the first. Several blocks rather than two halves: a core slowed by other work takes
//! fewer of them, and a machine with more cores runs more loops at once.
//!
//! The blocks are slabs along the bounding box's longest axis that hold equal numbers of
//! vertices. The faces with corners in several slabs (the seams) go into each of their blocks
//! with all their corners kept: each block then sees every face around each vertex it may
//! remove, its link and manifold checks see every edge those collapses touch, and the seams
//! come out of every block unchanged. The blocks' outputs are joined along the seams and
//! decimated to the target as one mesh, which removes the seams' vertices. That pass starts
//! from the quadrics the blocks summed (each vertex's from its own slab's block, the one that
//! sees all its faces), so its costs are those the whole mesh's loop would compute. The
//! output is the same for any thread count. An error bound (`max_error`) applies per pass,
//! not to the sum of what a vertex moved over the passes: such runs are decimated whole.

use std::borrow::Cow;
use std::cmp::Reverse;
use std::collections::HashSet;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use super::decimation::{
    Decimation, DecimationOptions, Target, decimate_whole, decimate_whole_with_quadrics,
};
use super::quadric::Quadric;
use crate::error::Result;

/// Slabs the mesh is cut into, whatever the thread count (so is the output). Eight: two
/// threads balance their load over them, and eight cores each run a loop; more would add
/// seams for the last pass to remove.
const BLOCKS: usize = 8;

/// Meshes with fewer faces are decimated whole: below, the threads, the join and the last pass
/// cost about what the parallel loops save (even at 82k faces, 10 % kept; docs/qem.md).
const BLOCKS_MIN_FACES: usize = 100_000;

/// Targets keeping more than this share of the faces are decimated whole: the last pass,
/// over a joined mesh nearly as large as the input, costs more than the parallel loops save
/// (at half the faces kept; a third still gains).
const BLOCKS_MAX_KEPT: f64 = 1.0 / 3.0;

/// Faces each block keeps beyond its share of the target and its seams, in seams: room for
/// the last pass to choose among, so the seams' collapses compete with the cheapest of the
/// rest. Without it, at 1 % of 1.3M faces cut in two (a 3k-face seam, 13k faces kept), the
/// output's mean squared distance to the input was 12 % above the whole loop's; with it, the
/// same.
const JOIN_ROOM_SEAMS: usize = 1;

/// The share of the progress the blocks report (their first decimation up to
/// `BLOCKS_FIRST_PROGRESS`, the over-decimated ones' second the rest); the pass over the
/// joined mesh the rest.
const BLOCKS_PROGRESS: f64 = 0.9;
const BLOCKS_FIRST_PROGRESS: f64 = 0.8;

/// A block whose costliest collapse exceeds this many times the blocks' median is decimated
/// again, capped at `OVER_DECIMATED_CAP` times the median ([`over_decimation_caps`]). Smooth
/// meshes stay below: the polar blocks of `bumpy8.ply` at 1 % reach 5.9× and 4.7×, face000.ply
/// at 10 % 6.1×; snowden.obj's pedestal 120× at 10 %, 4 600× at 7 %, 170 000× at 5 %. A redone
/// block costs time (at 4×, `bumpy8.ply` at 1 % took 1.54 s instead of 1.26 s).
const OVER_DECIMATED: f64 = 16.0;
const OVER_DECIMATED_CAP: f64 = 2.0;

/// The slab of a face whose corners lie in several.
const SEAM: u8 = u8::MAX;

/// One block as a mesh: its slab's faces and seam faces, over its vertices
/// ([`Split::members`]), and the seam corners it keeps.
struct Block {
    mesh: TriMesh,
    keep: Vec<u32>,
}

/// A block decimated: where its vertices went, and the quadrics of those left.
struct DecimatedBlock {
    decimation: Decimation,
    quadrics: Vec<Quadric>,
}

/// [`super::decimate`] of `mesh` as [`BLOCKS`] spatial blocks (on as many threads as rayon's
/// pool has, up to one per block), then the joined blocks to `target` faces. `None` when the
/// mesh has fewer than [`BLOCKS_MIN_FACES`] faces, the target keeps more than
/// [`BLOCKS_MAX_KEPT`] of them, `options.max_error` is set, or a slab holds no face of its own:
/// the caller decimates it whole.
pub(super) fn decimate_in_blocks(
    mesh: &TriMesh,
    options: &DecimationOptions,
    target: usize,
    progress: &mut dyn FnMut(f64),
) -> Option<Result<Decimation>> {
    let faces = mesh.face_count();
    if faces < BLOCKS_MIN_FACES
        || target as f64 > BLOCKS_MAX_KEPT * faces as f64
        || options.max_error.is_some()
    {
        return None;
    }
    let split = Split::new(mesh)?;
    let own_total: usize = split.own_faces.iter().sum();
    // Each block keeps its share of the target, its seams and the join's room.
    let targets: Vec<usize> = (0..BLOCKS)
        .map(|b| {
            let own = split.own_faces[b];
            let share = target as f64 * own as f64 / own_total as f64;
            share.round() as usize + (1 + JOIN_ROOM_SEAMS) * (split.faces[b].len() - own)
        })
        .collect();
    Some(decimate_blocks(
        mesh, options, target, &split, &targets, progress,
    ))
}

/// Where the slabs cut the mesh, and what each block holds.
struct Split {
    /// Per vertex: its slab.
    slab: Vec<u8>,
    /// Per vertex: a corner of a seam face (kept by every block that holds it).
    on_seam: Vec<bool>,
    /// Per vertex: its index in its own slab's block.
    home_local: Vec<u32>,
    /// Per block: its slab's vertices in input order, then the other slabs' corners of its
    /// seam faces in ascending order (block index → input vertex).
    members: Vec<Vec<u32>>,
    /// Per block: how many of `members` are its slab's.
    home_count: Vec<usize>,
    /// Per block, in input order: its slab's faces and the seam faces with a corner in it.
    faces: Vec<Vec<u32>>,
    /// Per block: how many of `faces` are its slab's alone.
    own_faces: Vec<usize>,
    /// The seam faces.
    seam_faces: Vec<u32>,
}

impl Split {
    /// Cuts `mesh` into [`BLOCKS`] slabs; `None` when a slab holds no face of its own.
    fn new(mesh: &TriMesh) -> Option<Self> {
        let slab = vertex_slabs(mesh);
        let triangles = mesh.triangles();
        let face_slab: Vec<u8> = triangles
            .par_iter()
            .map(|t| {
                let s = t.map(|v| slab[v as usize]);
                if s[0] == s[1] && s[1] == s[2] {
                    s[0]
                } else {
                    SEAM
                }
            })
            .collect();
        let mut faces = vec![Vec::new(); BLOCKS];
        let mut own_faces = vec![0; BLOCKS];
        let mut seam_faces = Vec::new();
        let mut on_seam = vec![false; slab.len()];
        for (f, (t, &s)) in triangles.iter().zip(&face_slab).enumerate() {
            if s != SEAM {
                faces[s as usize].push(f as u32);
                own_faces[s as usize] += 1;
                continue;
            }
            seam_faces.push(f as u32);
            let mut slabs = t.map(|v| slab[v as usize]);
            slabs.sort_unstable();
            for (k, &s) in slabs.iter().enumerate() {
                if k == 0 || s != slabs[k - 1] {
                    faces[s as usize].push(f as u32);
                }
            }
            for &v in t {
                on_seam[v as usize] = true;
            }
        }
        if own_faces.contains(&0) {
            return None;
        }
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); BLOCKS];
        let mut home_local = vec![0u32; slab.len()];
        for (v, &s) in slab.iter().enumerate() {
            home_local[v] = members[s as usize].len() as u32;
            members[s as usize].push(v as u32);
        }
        let home_count = members.iter().map(Vec::len).collect();
        for (b, block) in members.iter_mut().enumerate() {
            let mut foreign: Vec<u32> = faces[b]
                .iter()
                .filter(|&&f| face_slab[f as usize] == SEAM)
                .flat_map(|&f| triangles[f as usize])
                .filter(|&v| slab[v as usize] as usize != b)
                .collect();
            foreign.sort_unstable();
            foreign.dedup();
            block.extend(foreign);
        }
        Some(Self {
            slab,
            on_seam,
            home_local,
            members,
            home_count,
            faces,
            own_faces,
            seam_faces,
        })
    }

    /// Block `b`'s index of input vertex `v`, which the block holds.
    fn local(&self, b: usize, v: u32) -> u32 {
        let home = self.home_count[b];
        if self.slab[v as usize] as usize == b {
            return self.home_local[v as usize];
        }
        let foreign = &self.members[b][home..];
        (home + foreign.partition_point(|&u| u < v)) as u32
    }

    /// Block `b` as a mesh, with attributes.
    fn block(&self, mesh: &TriMesh, b: usize) -> Result<Block> {
        let members = &self.members[b];
        let faces = self.faces[b]
            .iter()
            .map(|&f| mesh.triangles()[f as usize].map(|v| self.local(b, v)))
            .collect();
        let built = TriMesh::new(subset(members, mesh.vertices()), faces)
            .and_then(|m| match mesh.normals() {
                Some(normals) => m.with_normals(subset(members, normals)),
                None => Ok(m),
            })
            .and_then(|m| match mesh.uvs() {
                Some(uvs) => m.with_uvs(subset(members, uvs)),
                None => Ok(m),
            })
            .and_then(|m| match mesh.colors() {
                Some(colors) => m.with_colors(subset(members, colors)),
                None => Ok(m),
            })?;
        let keep = (0..members.len() as u32)
            .filter(|&i| self.on_seam[members[i as usize] as usize])
            .collect();
        Ok(Block { mesh: built, keep })
    }

    /// The output vertex of block `b` (decimated as `blocks[b]`) that input vertex `v` became.
    fn output_of(&self, blocks: &[DecimatedBlock], b: usize, v: u32) -> u32 {
        blocks[b].decimation.vertex_map[self.local(b, v) as usize]
    }
}

/// `values` of the vertices `members`, in that order.
fn subset<T: Copy>(members: &[u32], values: &[T]) -> Vec<T> {
    members.iter().map(|&v| values[v as usize]).collect()
}

/// The slab of every vertex: the number of the [`BLOCKS`]` - 1` cuts at or below it along the
/// bounding box's longest axis, the cuts at equal vertex counts.
fn vertex_slabs(mesh: &TriMesh) -> Vec<u8> {
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
    coordinates.par_sort_unstable_by(f32::total_cmp);
    let cuts: Vec<f32> = (1..BLOCKS)
        .map(|k| coordinates[k * coordinates.len() / BLOCKS])
        .collect();
    drop(coordinates);
    vertices
        .par_iter()
        .map(|p| cuts.partition_point(|c| c.total_cmp(&p[axis]).is_le()) as u8)
        .collect()
}

/// Decimates the blocks, joins them and decimates the joined mesh to `target`.
fn decimate_blocks(
    mesh: &TriMesh,
    options: &DecimationOptions,
    target: usize,
    split: &Split,
    targets: &[usize],
    progress: &mut dyn FnMut(f64),
) -> Result<Decimation> {
    let all: Vec<usize> = (0..BLOCKS).collect();
    let uncapped = [None; BLOCKS];
    let mut blocks = decimate_each(mesh, options, split, targets, &uncapped, &all, &mut |f| {
        progress(BLOCKS_FIRST_PROGRESS * f)
    })
    .into_iter()
    .flatten()
    .collect::<Result<Vec<_>>>()?;
    let caps = over_decimation_caps(&blocks);
    let again: Vec<usize> = (0..BLOCKS).filter(|&b| caps[b].is_some()).collect();
    if !again.is_empty() {
        let redone = decimate_each(mesh, options, split, targets, &caps, &again, &mut |f| {
            progress(BLOCKS_FIRST_PROGRESS + (BLOCKS_PROGRESS - BLOCKS_FIRST_PROGRESS) * f)
        });
        for (b, block) in redone.into_iter().enumerate() {
            if let Some(block) = block {
                blocks[b] = block?;
            }
        }
    }
    let joined = join(mesh, split, &blocks)?;
    let whole = DecimationOptions {
        target: Target::Faces(target),
        ..*options
    };
    let last = decimate_whole(
        Cow::Owned(joined.mesh),
        &whole,
        &[],
        Some(&joined.quadrics),
        &mut |f| progress(BLOCKS_PROGRESS + (1.0 - BLOCKS_PROGRESS) * f),
    )?;
    let decimations = || blocks.iter().map(|b| &b.decimation).chain([&last]);
    let error = decimations().map(|d| d.error).fold(0.0, f64::max);
    let max_cost = decimations().map(|d| d.max_cost).fold(0.0, f64::max);
    let welded = decimations().any(|d| d.welded);
    let collapses = decimations().map(|d| d.collapses).sum();
    Ok(Decimation {
        vertex_map: joined
            .vertex_map
            .iter()
            .map(|&j| last.vertex_map[j as usize])
            .collect(),
        error,
        error_distance: error.sqrt(),
        max_cost,
        welded,
        stop_reason: last.stop_reason,
        input_faces: mesh.face_count(),
        input_vertices: mesh.vertex_count(),
        collapses,
        mesh: last.mesh,
    })
}

/// The cost caps of the blocks decimated past where the whole mesh's loop would stop in their
/// region. Each block is decimated to its share of the target, in proportion to its faces;
/// the whole mesh's loop instead removes the cheapest collapses anywhere, so a block of fine
/// detail or thin walls keeps more than its share and a smooth one less. A block whose
/// costliest collapse exceeds [`OVER_DECIMATED`] times the blocks' median was forced far
/// past that point: it is decimated again, capped at [`OVER_DECIMATED_CAP`] times the median,
/// and the last pass, which orders its remaining collapses among the other blocks', does the
/// rest. On snowden.obj (a hollow bust on a thin-walled pedestal, the pedestal one block) at
/// 5 % the output's mean squared distance to the input falls from 4.2e-6 to 5.7e-7.
fn over_decimation_caps(blocks: &[DecimatedBlock]) -> [Option<f64>; BLOCKS] {
    let mut costs: Vec<f64> = blocks.iter().map(|b| b.decimation.max_cost).collect();
    costs.sort_by(f64::total_cmp);
    let median = costs[BLOCKS / 2];
    std::array::from_fn(|b| {
        (blocks[b].decimation.max_cost > OVER_DECIMATED * median)
            .then_some(OVER_DECIMATED_CAP * median)
    })
}

/// The blocks `which` built and decimated to their targets (none costing more than its cap),
/// largest first (so the last ones taken are small and the threads finish together): by as
/// many threads as rayon's pool has (up to one per block), each with a one-thread pool of its
/// own, taking the next block as they free up; with one, one after the other. A block's mesh
/// is freed once its collapse loop holds the data. The blocks' progress reaches `progress` on
/// this thread, through a channel. The result of block `b` is at `b`, `None` if not in `which`.
fn decimate_each(
    mesh: &TriMesh,
    options: &DecimationOptions,
    split: &Split,
    targets: &[usize],
    caps: &[Option<f64>; BLOCKS],
    which: &[usize],
    progress: &mut dyn FnMut(f64),
) -> Vec<Option<Result<DecimatedBlock>>> {
    let run = |b: usize, report: &mut dyn FnMut(f64)| {
        let Block { mesh, keep } = split.block(mesh, b)?;
        let block_options = DecimationOptions {
            target: Target::Faces(targets[b]),
            ..*options
        };
        let (decimation, quadrics) =
            decimate_whole_with_quadrics(Cow::Owned(mesh), &block_options, &keep, caps[b], report)?;
        Ok(DecimatedBlock {
            decimation,
            quadrics,
        })
    };
    let mut order = which.to_vec();
    order.sort_by_key(|&b| Reverse(split.faces[b].len()));
    let weights: Vec<f64> = (0..BLOCKS)
        .map(|b| {
            if which.contains(&b) {
                split.faces[b].len() as f64
            } else {
                0.0
            }
        })
        .collect();
    let total: f64 = weights.iter().sum();
    let mut done = vec![0.0; BLOCKS];
    let mut report = |b: usize, f: f64| {
        done[b] = f;
        let share: f64 = weights.iter().zip(&done).map(|(w, d)| w * d).sum();
        progress(share / total);
    };
    let threads = rayon::current_num_threads().min(BLOCKS);
    let mut results: Vec<Option<Result<DecimatedBlock>>> = (0..BLOCKS).map(|_| None).collect();
    if threads < 2 {
        for &b in &order {
            results[b] = Some(run(b, &mut |f| report(b, f)));
        }
    } else {
        let next = AtomicUsize::new(0);
        let (sender, receiver) = mpsc::channel::<(usize, f64)>();
        let finished = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|_| {
                    let sender = sender.clone();
                    let (run, next, order) = (&run, &next, &order);
                    scope.spawn(move || {
                        let work = || {
                            let mut out = Vec::new();
                            while let Some(&b) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                                // The receiver lives until every block is decimated.
                                let mut report = |f: f64| {
                                    let _ = sender.send((b, f));
                                };
                                out.push((b, run(b, &mut report)));
                            }
                            out
                        };
                        match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                            Ok(pool) => pool.install(work),
                            Err(_) => work(),
                        }
                    })
                })
                .collect();
            drop(sender);
            for (b, f) in receiver {
                report(b, f);
            }
            handles
                .into_iter()
                .flat_map(|h| {
                    h.join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                })
                .collect::<Vec<_>>()
        });
        for (b, result) in finished {
            results[b] = Some(result);
        }
    }
    results
}

/// The blocks' outputs as one mesh, where each input vertex went in it, and the quadric of
/// each of its vertices.
struct Joined {
    mesh: TriMesh,
    vertex_map: Vec<u32>,
    quadrics: Vec<Quadric>,
}

/// Joins the blocks' outputs: per block, its output vertices but those of other slabs' seam
/// corners (which their own block holds too, unmoved), and the faces of all, each seam face
/// once. A vertex's quadric and attributes come from its own slab's block: another block holds
/// a seam corner with only the seam's faces, and nothing collapses onto it there.
fn join(mesh: &TriMesh, split: &Split, blocks: &[DecimatedBlock]) -> Result<Joined> {
    let outputs: Vec<&TriMesh> = blocks.iter().map(|b| &b.decimation.mesh).collect();
    // Per block and output vertex: its joined index; other slabs' corners filled in after.
    let mut joined_index: Vec<Vec<u32>> = outputs
        .iter()
        .map(|m| vec![u32::MAX; m.vertex_count()])
        .collect();
    for (b, index) in joined_index.iter_mut().enumerate() {
        for &v in &split.members[b][split.home_count[b]..] {
            index[split.output_of(blocks, b, v) as usize] = u32::MAX - 1;
        }
    }
    // The joined vertices: (block, output vertex) of each.
    let mut owners: Vec<(usize, u32)> = Vec::new();
    for (b, index) in joined_index.iter_mut().enumerate() {
        for (o, slot) in index.iter_mut().enumerate() {
            if *slot == u32::MAX {
                *slot = owners.len() as u32;
                owners.push((b, o as u32));
            }
        }
    }
    // Each input vertex's joined index: its own slab's block's output's.
    let vertex_map: Vec<u32> = (0..mesh.vertex_count() as u32)
        .map(|v| {
            let b = split.slab[v as usize] as usize;
            joined_index[b][split.output_of(blocks, b, v) as usize]
        })
        .collect();
    for (b, index) in joined_index.iter_mut().enumerate() {
        for &v in &split.members[b][split.home_count[b]..] {
            index[split.output_of(blocks, b, v) as usize] = vertex_map[v as usize];
        }
    }
    let mut on_seam = vec![false; owners.len()];
    let seam: HashSet<[u32; 3]> = split
        .seam_faces
        .iter()
        .map(|&f| {
            let t = mesh.triangles()[f as usize].map(|v| vertex_map[v as usize]);
            for j in t {
                on_seam[j as usize] = true;
            }
            sorted(t)
        })
        .collect();
    let mut emitted = HashSet::with_capacity(seam.len());
    let mut faces = Vec::new();
    for (output, index) in outputs.iter().zip(&joined_index) {
        for t in output.triangles() {
            let joined = t.map(|o| index[o as usize]);
            let seam_face = joined.iter().all(|&j| on_seam[j as usize]) && {
                let key = sorted(joined);
                seam.contains(&key) && !emitted.insert(key)
            };
            if !seam_face {
                faces.push(joined);
            }
        }
    }
    let positions = owners
        .iter()
        .map(|&(b, o)| outputs[b].vertices()[o as usize])
        .collect();
    let mut joined = TriMesh::new(positions, faces)?;
    if let Some(normals) = gathered(&owners, &outputs, TriMesh::normals) {
        joined = joined.with_normals(normals)?;
    }
    if let Some(uvs) = gathered(&owners, &outputs, TriMesh::uvs) {
        joined = joined.with_uvs(uvs)?;
    }
    if let Some(colors) = gathered(&owners, &outputs, TriMesh::colors) {
        joined = joined.with_colors(colors)?;
    }
    let quadrics = owners
        .iter()
        .map(|&(b, o)| blocks[b].quadrics[o as usize])
        .collect();
    Ok(Joined {
        mesh: joined,
        vertex_map,
        quadrics,
    })
}

/// Per joined vertex (block, output vertex): its value of `values`, when every output has them.
fn gathered<T: Copy>(
    owners: &[(usize, u32)],
    outputs: &[&TriMesh],
    values: impl Fn(&TriMesh) -> Option<&[T]>,
) -> Option<Vec<T>> {
    owners
        .iter()
        .map(|&(b, o)| values(outputs[b]).map(|v| v[o as usize]))
        .collect()
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

    /// `mesh` decimated to `target` faces in blocks, and whole.
    fn blocks_and_whole(mesh: &TriMesh, target: usize) -> (Decimation, Decimation) {
        let blocks = decimate_in_blocks(mesh, &options(target), target, &mut |_| {})
            .expect("large enough to split")
            .unwrap();
        let whole = decimate_whole(
            Cow::Borrowed(mesh),
            &options(target),
            &[],
            None,
            &mut |_| {},
        )
        .unwrap();
        (blocks, whole)
    }

    #[test]
    fn blocks_give_a_closed_ball_as_good_as_the_whole_loop() {
        let ball = bumpy_ball();
        assert!(ball.face_count() >= BLOCKS_MIN_FACES);
        for target in [10_000, 1_000] {
            let (blocks, whole) = blocks_and_whole(&ball, target);
            assert_eq!(blocks.mesh.face_count(), whole.mesh.face_count());
            let (edges, flipped) = edge_counts(&blocks.mesh);
            assert!(
                edges.values().all(|&c| c == 2) && !flipped,
                "target {target}"
            );
            // Euler characteristic of a sphere.
            let v = blocks.mesh.vertex_count() as i64;
            assert_eq!(v - edges.len() as i64 + blocks.mesh.face_count() as i64, 2);
            // The quadric error of the worst collapse, against the whole loop's.
            assert!(
                blocks.error <= 1.5 * whole.error,
                "target {target}: {} against {}",
                blocks.error,
                whole.error
            );
            assert_eq!(blocks.vertex_map.len(), ball.vertex_count());
            assert!(blocks.vertex_map.iter().all(|&o| (o as usize) < v as usize));
        }
    }

    #[test]
    fn a_block_of_detail_among_flat_ones_is_decimated_as_the_whole_loop_would() {
        // A flat strip 8 long, 102 400 faces, with bumps on its last eighth only: the slab
        // there holds all the detail. Decimated to its share of the target (an eighth), that
        // block would go far past what the whole loop removes there.
        let grid = grid_plane(800, 64);
        let vertices = grid
            .vertices()
            .iter()
            .map(|&[x, y, _]| {
                let x = 8.0 * x;
                let z = if x > 7.0 {
                    0.02 * (30.0 * x).sin() * (30.0 * y).sin()
                } else {
                    0.0
                };
                [x, y, z]
            })
            .collect();
        let strip = grid.with_vertices(vertices).unwrap();
        assert!(strip.face_count() >= BLOCKS_MIN_FACES);
        let target = 2_000;
        let (blocks, whole) = blocks_and_whole(&strip, target);
        assert_eq!(blocks.mesh.face_count(), whole.mesh.face_count());
        // The whole loop spends nearly all the faces on the bumps; so must the blocks.
        let on_bumps = |mesh: &TriMesh| {
            let x = |v: u32| mesh.vertices()[v as usize][0];
            let faces = mesh.triangles().iter();
            faces.filter(|t| t.iter().all(|&v| x(v) > 7.0)).count()
        };
        let (blocks_on_bumps, whole_on_bumps) = (on_bumps(&blocks.mesh), on_bumps(&whole.mesh));
        assert!(
            blocks_on_bumps as f64 >= 0.9 * whole_on_bumps as f64,
            "{blocks_on_bumps} faces on the bumps against {whole_on_bumps}"
        );
    }

    #[test]
    fn the_slabs_hold_equal_vertex_counts_and_each_seam_face_is_in_its_corners_blocks() {
        let ball = bumpy_ball();
        let split = Split::new(&ball).expect("every slab holds faces");
        let n = ball.vertex_count();
        // Equal up to the vertices tied with a cut's coordinate (the ball is symmetric).
        for &count in &split.home_count {
            assert!(count.abs_diff(n / BLOCKS) <= n / 100, "{count} of {n}");
        }
        assert_eq!(split.home_count.iter().sum::<usize>(), n);
        let mut seen = vec![0usize; ball.face_count()];
        for (b, faces) in split.faces.iter().enumerate() {
            for &f in faces {
                let t = ball.triangles()[f as usize];
                assert!(t.iter().any(|&v| split.slab[v as usize] as usize == b));
                // Every corner is one of the block's vertices, at its index.
                for v in t {
                    let local = split.local(b, v) as usize;
                    assert_eq!(split.members[b][local], v);
                }
                seen[f as usize] += 1;
            }
        }
        for (f, &count) in seen.iter().enumerate() {
            let mut slabs = ball.triangles()[f].map(|v| split.slab[v as usize]);
            slabs.sort_unstable();
            let distinct =
                1 + usize::from(slabs[0] != slabs[1]) + usize::from(slabs[1] != slabs[2]);
            assert_eq!(count, distinct, "face {f}");
            assert_eq!(
                split.seam_faces.binary_search(&(f as u32)).is_ok(),
                distinct > 1
            );
        }
        assert!(!split.seam_faces.is_empty());
    }

    #[test]
    fn a_triangle_soup_is_welded_across_the_cuts() {
        // Every face with vertices of its own: the copies of a position on a seam must land
        // on the one kept vertex in each block, or the blocks would tear apart.
        let ball = bumpy_ball();
        let vertices = (0..ball.face_count())
            .flat_map(|f| ball.triangle_positions(f))
            .collect();
        let triangles = (0..ball.face_count() as u32)
            .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
            .collect();
        let soup = TriMesh::new(vertices, triangles).unwrap();
        let out = decimate_in_blocks(&soup, &options(2_000), 2_000, &mut |_| {})
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
    fn blocks_give_the_same_output_for_any_thread_count() {
        let ball = bumpy_ball();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| decimate(&ball, &options(5_000)).unwrap())
        };
        let one = run(1);
        assert_eq!(run(2), one);
        assert_eq!(run(3), one);
    }

    #[test]
    fn blocks_keep_an_open_border() {
        // 105 800 faces: the border vertices stay on the square's border through the blocks
        // and the last pass (attributes through the blocks: tests/qem_decimation.rs).
        let grid = grid_plane(230, 230);
        let out = decimate_in_blocks(&grid, &options(2_000), 2_000, &mut |_| {})
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
        assert!(decimate_in_blocks(&grid, &options(2_000), 2_000, &mut |_| {}).is_none());
        assert!(decimate_in_blocks(&ball, &options(faces / 2), faces / 2, &mut |_| {}).is_none());
        let bounded = DecimationOptions {
            max_error: Some(0.01),
            ..options(1_000)
        };
        assert!(decimate_in_blocks(&ball, &bounded, 1_000, &mut |_| {}).is_none());
    }
}
