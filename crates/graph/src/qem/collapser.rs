//! The mutable state of QEM decimation (Garland & Heckbert, SIGGRAPH 1997; thesis ch. 2.3.2):
//! compact vertex records, per-vertex quadrics, the faces and a flat vertex → face incidence
//! list, and the edge collapse that updates them. The placement of a collapse lives in
//! `edge_placement.rs`, its validity checks in `collapse_checks.rs`, the passes in
//! `decimation.rs`.
//!
//! # Layout
//! Everything the collapse loop reads for a vertex (position, region normal, where its
//! incidence list is, flags) sits in one 32-byte, 32-aligned [`VertexRecord`], so a vertex
//! costs one cache-line fetch; quadrics (80 bytes, needed only to score an edge) are a
//! separate array. Dead faces and vertices are marked in place, not in side arrays.

use meshgnn_geometry::TriMesh;
use meshgnn_geometry::vec3::{cross, dot, sub};
use rayon::prelude::*;

use super::decimation::{Decimation, DecimationOptions, StopReason};
use super::quadric::Quadric;
use super::weld_by_position::{twins_of, weld_by_position};
use crate::error::{Error, Result};

/// Marks a dead face (`faces[f] = [DEAD; 3]`).
pub(crate) const DEAD: u32 = u32::MAX;
/// Vertex flag: on a UV seam (one position, several UVs): never moved, and removed only along
/// the seam together with its twins (`Collapser::twin_collapses`).
pub(crate) const LOCKED: u32 = 1;
/// Vertex flag: on an edge with one face (the open boundary; kept current as collapses merge
/// edges, `Collapser::refresh_edge_flags`).
pub(crate) const BOUNDARY: u32 = 2;
/// Vertex flag: removed by a collapse.
const REMOVED: u32 = 4;
/// Vertex flag: on an edge with three or more faces (kept current like [`BOUNDARY`]). Such a
/// vertex stays where it is and is removed only along a non-manifold edge, by the checks of
/// `collapse_checks.rs` that keep every edge's face count from growing.
pub(crate) const NON_MANIFOLD: u32 = 8;
/// Vertex flag: kept by the caller ([`super::decimate_keeping`]): never removed, never moved;
/// other vertices may collapse onto it.
const KEPT: u32 = 16;
/// The flags' bits of [`VertexRecord::meta`]; the incidence list length is stored above them.
const FLAG_BITS: u32 = 5;
/// The largest supported face count: incidence offsets are `u32` (`refs` stays below
/// `4 · #F + 1024` plus one batch of fans) and a vertex's face count fits in
/// `32 − FLAG_BITS` bits.
const MAX_FACES: usize = 250_000_000;
/// Room in `refs` beyond [`refs_limit`]: the fans appended by the batch of collapses that
/// crosses it (up to 1024 collapses of ~12 faces each).
const REFS_SLACK: usize = 1 << 16;
/// Vertices per parallel task of the setup's edge enumeration.
const EDGE_CHUNK: usize = 2048;

/// The hot per-vertex data of the collapse loop, one half cache line.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(32))]
pub(crate) struct VertexRecord {
    /// Current position (the output precision: checks run on exactly what is written).
    pub position: [f32; 3],
    /// Sum of the (doubled-)area normals of the input faces around the input vertices this
    /// vertex represents: the orientation of the input surface it stands for.
    pub region_normal: [f32; 3],
    /// Start of this vertex's incident faces in [`Collapser::refs`].
    pub start: u32,
    /// `len << FLAG_BITS | flags`: the number of incident faces (which may include dead
    /// ones) and [`LOCKED`] | [`BOUNDARY`] | `REMOVED` | [`NON_MANIFOLD`] | `KEPT`.
    pub meta: u32,
}

impl VertexRecord {
    pub(crate) fn alive(&self) -> bool {
        self.meta & REMOVED == 0
    }

    pub(crate) fn locked(&self) -> bool {
        self.meta & LOCKED != 0
    }

    pub(crate) fn boundary(&self) -> bool {
        self.meta & BOUNDARY != 0
    }

    pub(crate) fn non_manifold(&self) -> bool {
        self.meta & NON_MANIFOLD != 0
    }

    pub(crate) fn kept(&self) -> bool {
        self.meta & KEPT != 0
    }

    /// The range of `refs` holding the incident faces.
    pub(crate) fn incident(&self) -> std::ops::Range<usize> {
        let start = self.start as usize;
        start..start + (self.meta >> FLAG_BITS) as usize
    }

    /// Points the incidence list at `refs[start..start + len]`.
    fn set_incident(&mut self, start: usize, len: usize) {
        self.start = start as u32;
        self.meta = (len as u32) << FLAG_BITS | (self.meta & ((1 << FLAG_BITS) - 1));
    }

    pub(crate) fn point(&self) -> [f64; 3] {
        self.position.map(f64::from)
    }
}

/// Where an edge collapses to.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Placement {
    pub cost: f64,
    /// Rounded to `f32` before scoring, so the cost and the checks see the output position.
    pub position: [f32; 3],
    /// The endpoint that survives.
    pub survivor: u32,
    /// Parameter of `position` along `a → b`, for attribute interpolation.
    pub t: f64,
}

#[inline]
fn lerp<const N: usize>(a: [f32; N], b: [f32; N], t: f64) -> [f32; N] {
    std::array::from_fn(|i| (f64::from(a[i]) * (1.0 - t) + f64::from(b[i]) * t) as f32)
}

fn normalized(v: [f32; 3]) -> [f32; 3] {
    let n = v
        .iter()
        .map(|x| f64::from(*x) * f64::from(*x))
        .sum::<f64>()
        .sqrt();
    if n > 0.0 {
        v.map(|x| (f64::from(x) / n) as f32)
    } else {
        v
    }
}

/// Connectivity, quadrics and attributes of a mesh being decimated.
pub(crate) struct Collapser {
    pub verts: Vec<VertexRecord>,
    pub quadrics: Vec<Quadric>,
    /// `[DEAD; 3]` once removed.
    pub faces: Vec<[u32; 3]>,
    pub live_faces: usize,
    /// Incident faces of vertex `v`: `refs[verts[v].incident()]` (may hold dead faces,
    /// skipped on use).
    pub refs: Vec<u32>,
    parent: Vec<u32>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
    colors: Option<Vec<[f32; 3]>>,
    weld_map: Vec<u32>,
    /// The next vertex at the same position (a UV seam's twins, cyclic; itself elsewhere).
    pub twin: Vec<u32>,
    welded: bool,
    /// The setup's edges, in chunks of vertices, scored in the first pass.
    pub initial_edges: Vec<Vec<(u32, u32)>>,
    scratch_faces: Vec<u32>,
    /// Neighbours whose flags the last collapse changed (see [`Self::refresh_edge_flags`]).
    refreshed: Vec<u32>,
    pub max_cost: f64,
    pub max_error: f64,
    pub collapses: usize,
    pub keep_original_positions: bool,
    /// The input's face and vertex counts, for [`Decimation`].
    input_size: (usize, usize),
}

impl Collapser {
    /// Welds `mesh`, builds the incidence lists, quadrics (area-weighted face planes plus
    /// boundary planes, or the sums of `given` per welded vertex: the quadrics of a mesh
    /// decimated before), region normals, flags (the input vertices `keep` kept) and the list
    /// of collapsible edges.
    pub(crate) fn new(
        mesh: &TriMesh,
        options: &DecimationOptions,
        keep: &[u32],
        given: Option<&[Quadric]>,
    ) -> Result<Self> {
        if let Some(&v) = keep.iter().find(|&&v| v as usize >= mesh.vertex_count()) {
            return Err(Error::InvalidParameter {
                name: "keep",
                message: format!(
                    "vertex {v} to keep is outside the mesh's {} vertices",
                    mesh.vertex_count()
                ),
            });
        }
        if mesh.face_count() > MAX_FACES || mesh.vertex_count() >= DEAD as usize {
            return Err(Error::UnusableMesh {
                what: "mesh to decimate".into(),
                message: format!(
                    "{} triangles, {} vertices; decimation supports at most {MAX_FACES} \
                     triangles and {DEAD} vertices: split it first",
                    mesh.face_count(),
                    mesh.vertex_count()
                ),
            });
        }
        let welding = weld_by_position(mesh.vertices(), mesh.uvs());
        let reps = &welding.representatives;
        let n = reps.len();
        let positions: Vec<[f64; 3]> = reps
            .par_iter()
            .map(|&r| mesh.vertices()[r as usize].map(f64::from))
            .collect();
        let mut faces: Vec<[u32; 3]> = mesh
            .triangles()
            .par_iter()
            .map(|t| t.map(|v| welding.map[v as usize]))
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .collect();

        // Attributes of welded vertices: UVs equal by construction; normals/colours averaged.
        let average3 = |values: &[[f32; 3]], unit: bool| -> Vec<[f32; 3]> {
            let mut sum = vec![[0f64; 3]; n];
            let mut count = vec![0u32; n];
            for (i, v) in values.iter().enumerate() {
                let w = welding.map[i] as usize;
                for k in 0..3 {
                    sum[w][k] += f64::from(v[k]);
                }
                count[w] += 1;
            }
            sum.iter()
                .zip(&count)
                .map(|(s, &c)| {
                    let m = s.map(|x| (x / f64::from(c.max(1))) as f32);
                    if unit { normalized(m) } else { m }
                })
                .collect()
        };
        let normals = mesh.normals().map(|v| average3(v, true));
        let colors = mesh.colors().map(|v| average3(v, false));
        let uvs = mesh
            .uvs()
            .map(|u| reps.iter().map(|&r| u[r as usize]).collect::<Vec<_>>());

        // Vertex → face incidence (CSR, faces in increasing order).
        let mut links = vec![(0u32, 0u32); n];
        for f in &faces {
            for &v in f {
                links[v as usize].1 += 1;
            }
        }
        let mut total = 0u32;
        for link in &mut links {
            link.0 = total;
            total += link.1;
        }
        let mut refs = Vec::with_capacity(refs_limit(faces.len()) + REFS_SLACK);
        refs.resize(total as usize, 0u32);
        let mut fill: Vec<u32> = links.iter().map(|l| l.0).collect();
        for (fi, f) in faces.iter().enumerate() {
            for &v in f {
                refs[fill[v as usize] as usize] = fi as u32;
                fill[v as usize] += 1;
            }
        }
        drop(fill);

        // A face on the same three vertices as an earlier one adds no surface, only
        // non-manifold edges (scans hold such doubled sheets): it is dropped. Found from the
        // incidence list of the face's smallest vertex.
        let repeats: Vec<u32> = (0..faces.len() as u32)
            .into_par_iter()
            .filter(|&f| {
                let face = faces[f as usize];
                let (start, len) = links[*face.iter().min().unwrap_or(&0) as usize];
                refs[start as usize..(start + len) as usize]
                    .iter()
                    .take_while(|&&g| g < f)
                    .any(|&g| face.iter().all(|v| faces[g as usize].contains(v)))
            })
            .collect();
        for &f in &repeats {
            faces[f as usize] = [DEAD; 3];
        }
        let live = |f: &&u32| faces[**f as usize][0] != DEAD;

        // Per vertex, in CSR order (deterministic): the area-weighted face plane quadrics
        // (unless `given`), and the vertex record with the sum of the face area normals (flags
        // follow below). (Face planes are recomputed per incident vertex rather than stored:
        // 3× the arithmetic, but no per-face array at the memory peak.)
        let corner_normal = |[p0, p1, p2]: [[f64; 3]; 3]| (cross(sub(p1, p0), sub(p2, p0)), p0);
        let (mut quadrics, mut verts): (Vec<Quadric>, Vec<VertexRecord>) = (0..n)
            .into_par_iter()
            .map(|v| {
                let (start, len) = links[v];
                let (quadric, region) = refs[start as usize..(start + len) as usize]
                    .iter()
                    .filter(live)
                    .fold((Quadric::default(), [0.0; 3]), |(q, s), &f| {
                        let corners = faces[f as usize].map(|u| positions[u as usize]);
                        let (normal, point) = corner_normal(corners);
                        let q = match given {
                            Some(_) => q,
                            None => {
                                let area = 0.5 * dot(normal, normal).sqrt();
                                q + Quadric::from_plane(normal, point, area)
                            }
                        };
                        (q, std::array::from_fn(|k| s[k] + normal[k]))
                    });
                let record = VertexRecord {
                    position: positions[v].map(|x| x as f32),
                    region_normal: region.map(|x| x as f32),
                    start,
                    meta: len << FLAG_BITS | if welding.seam[v] { LOCKED } else { 0 },
                };
                (quadric, record)
            })
            .unzip();
        // From here on positions are read from the records (the same f32 values).
        drop(positions);
        drop(links);
        let position = |v: u32| verts[v as usize].point();

        // Undirected edges `(a < b)`, enumerated per vertex from the incidence lists (parallel,
        // no global sort), in chunks of vertices with one scratch list each: the collapsible
        // edges, and apart the boundary and non-manifold ones as
        // `(a, b, face count, first face)`. The chunks are kept as they are, not concatenated:
        // a second copy of every edge would sit at the decimation's memory peak.
        type Special = (u32, u32, u32, u32);
        type EdgeChunk = (Vec<(u32, u32)>, Vec<Special>);
        let chunks: Vec<EdgeChunk> = (0..n.div_ceil(EDGE_CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let vertices = chunk * EDGE_CHUNK..n.min((chunk + 1) * EDGE_CHUNK);
                let mut edges = Vec::with_capacity(3 * vertices.len());
                let mut special = Vec::new();
                let mut local: Vec<(u32, u32)> = Vec::new();
                for a in vertices {
                    local.clear();
                    for &f in refs[verts[a].incident()].iter().filter(live) {
                        for x in faces[f as usize] {
                            if x as usize > a {
                                local.push((x, f));
                            }
                        }
                    }
                    local.sort_unstable();
                    let mut i = 0;
                    while i < local.len() {
                        let mut j = i + 1;
                        while j < local.len() && local[j].0 == local[i].0 {
                            j += 1;
                        }
                        let (a, b) = (a as u32, local[i].0);
                        edges.push((a, b));
                        if j - i != 2 {
                            special.push((a, b, (j - i) as u32, local[i].1));
                        }
                        i = j;
                    }
                }
                (edges, special)
            })
            .collect();
        // A seam vertex stands for the whole surface around its position: the face planes of
        // its twins' charts join its quadric (equal for all twins, and kept equal since twins
        // collapse together). Quadrics `given` are summed over each welded vertex instead.
        if let Some(given) = given {
            for (&w, &q) in welding.map.iter().zip(given) {
                quadrics[w as usize] += q;
            }
        } else if welding.seam.contains(&true) {
            let own = quadrics.clone();
            for v in (0..n).filter(|&v| welding.seam[v]) {
                for t in twins_of(&welding.twin, v as u32) {
                    quadrics[v] += own[t as usize];
                }
            }
        }
        let mut flags: Vec<(u32, u32)> = Vec::new();
        for &(a, b, count, f) in chunks.iter().flat_map(|(_, special)| special) {
            if count == 1 {
                flags.push((a, BOUNDARY));
                flags.push((b, BOUNDARY));
                // A seam is no border of the surface: no border plane along it. Quadrics
                // `given` hold their border planes already.
                if given.is_some() || (welding.seam[a as usize] && welding.seam[b as usize]) {
                    continue;
                }
                let (normal, _) = corner_normal(faces[f as usize].map(position));
                let q = Quadric::border_plane(
                    position(a),
                    position(b),
                    normal,
                    options.boundary_weight,
                );
                quadrics[a as usize] += q;
                quadrics[b as usize] += q;
            } else {
                flags.push((a, NON_MANIFOLD));
                flags.push((b, NON_MANIFOLD));
            }
        }
        for (v, flag) in flags {
            verts[v as usize].meta |= flag;
        }
        // A kept position keeps all its twins (they collapse together).
        for &v in keep {
            let w = welding.map[v as usize];
            for t in std::iter::once(w).chain(twins_of(&welding.twin, w)) {
                verts[t as usize].meta |= KEPT;
            }
        }
        let edges = chunks.into_iter().map(|(edges, _)| edges).collect();

        let live_faces = faces.len() - repeats.len();
        Ok(Self {
            verts,
            quadrics,
            faces,
            live_faces,
            refs,
            parent: (0..n as u32).collect(),
            normals,
            uvs,
            colors,
            welded: welding.merged_any(),
            weld_map: welding.map,
            twin: welding.twin,
            initial_edges: edges,
            scratch_faces: Vec::new(),
            refreshed: Vec::new(),
            max_cost: 0.0,
            max_error: 0.0,
            collapses: 0,
            keep_original_positions: options.keep_original_positions,
            input_size: (mesh.face_count(), mesh.vertex_count()),
        })
    }

    /// The range of `refs` holding the incident faces of `v`.
    pub(crate) fn incident(&self, v: u32) -> std::ops::Range<usize> {
        self.verts[v as usize].incident()
    }

    /// Whether collapsing `(a, b)` at `cost` exceeds the bound `max_error2` on the normalised
    /// cost (length², see `Decimation::error`).
    pub(crate) fn exceeds_error(&self, a: u32, b: u32, cost: f64, max_error2: Option<f64>) -> bool {
        let weight = (self.quadrics[a as usize] + self.quadrics[b as usize]).weight();
        max_error2.is_some_and(|limit| weight > 0.0 && cost / weight > limit)
    }

    /// The number of live faces holding both `a` and `b`: the face count of edge `(a, b)`.
    pub(crate) fn edge_face_count(&self, a: u32, b: u32) -> usize {
        self.refs[self.incident(a)]
            .iter()
            .filter(|&&f| {
                let face = self.faces[f as usize];
                face[0] != DEAD && face.contains(&b)
            })
            .count()
    }

    /// Collapses `(a, b)` at `placement` and updates the connectivity.
    pub(crate) fn collapse(&mut self, a: u32, b: u32, placement: Placement) {
        let s = placement.survivor;
        let r = if s == a { b } else { a };
        let (is, ir) = (s as usize, r as usize);
        // Faces of r: remove those shared with s, re-point the others to s.
        self.scratch_faces.clear();
        self.refreshed.clear();
        for k in self.incident(r) {
            let f = self.refs[k] as usize;
            let face = &mut self.faces[f];
            if face[0] == DEAD {
                continue;
            }
            if face.contains(&s) {
                // The apex may lose its last edges to r and s, and with them its flags.
                self.refreshed
                    .extend(face.iter().filter(|&&x| x != r && x != s));
                *face = [DEAD; 3];
                self.live_faces -= 1;
            } else {
                for v in face.iter_mut() {
                    if *v == r {
                        *v = s;
                    }
                }
                self.scratch_faces.push(f as u32);
            }
        }
        // New incidence list of s: its live faces, then r's, appended to `refs`.
        let start = self.refs.len();
        for k in self.incident(s) {
            let f = self.refs[k];
            if self.faces[f as usize][0] != DEAD {
                self.refs.push(f);
            }
        }
        self.refs.extend_from_slice(&self.scratch_faces);
        let len = self.refs.len() - start;
        self.verts[is].set_incident(start, len);
        self.verts[ir].set_incident(0, 0);

        // Attributes at the placement's parameter along a → b.
        let t = placement.t;
        let (ia, ib) = (a as usize, b as usize);
        if let Some(n) = &mut self.normals {
            n[is] = normalized(lerp(n[ia], n[ib], t));
        }
        if let Some(u) = &mut self.uvs {
            u[is] = lerp(u[ia], u[ib], t);
        }
        if let Some(c) = &mut self.colors {
            c[is] = lerp(c[ia], c[ib], t);
        }
        let q = self.quadrics[is] + self.quadrics[ir];
        self.quadrics[is] = q;
        let removed = self.verts[ir];
        // Twins share one quadric: what a seam vertex absorbs from its own chart, its twins
        // absorb too (a seam pair collapse adds each side's equal share itself).
        if self.verts[is].locked() && !removed.locked() {
            let absorbed = self.quadrics[ir];
            for t in twins_of(&self.twin, s) {
                self.quadrics[t as usize] += absorbed;
            }
        }
        let survivor = &mut self.verts[is];
        survivor.position = placement.position;
        survivor.region_normal =
            std::array::from_fn(|k| survivor.region_normal[k] + removed.region_normal[k]);
        survivor.meta |= removed.meta & (BOUNDARY | NON_MANIFOLD);
        let flagged = survivor.meta & (BOUNDARY | NON_MANIFOLD) != 0;
        self.verts[ir].meta |= REMOVED;
        self.parent[ir] = s;
        self.collapses += 1;
        self.max_cost = self.max_cost.max(placement.cost);
        let weight = q.weight();
        if weight > 0.0 {
            self.max_error = self.max_error.max(placement.cost / weight);
        }
        if flagged {
            self.refresh_edge_flags(s);
        } else {
            self.refreshed.clear();
        }
    }

    /// Re-derives the border and non-manifold flags of `s` and of its flagged neighbours (and
    /// of the apexes in `refreshed`) from the face counts of their edges now: collapses along
    /// a scan's doubled sheets and ragged borders merge a one-face edge with a three-face one
    /// into a manifold edge (`1 + 3 − 2`), and a flag left on such a vertex would pin it for
    /// good (dragon_res3.ply kept 1 642 of its 1 737 vertices flagged at 1 %, 84 truly on such
    /// edges). Leaves in `refreshed` the neighbours whose flags changed; a valid collapse only
    /// clears theirs.
    fn refresh_edge_flags(&mut self, s: u32) {
        let mut around = std::mem::take(&mut self.refreshed);
        let mut ring = Vec::new();
        self.ring_into(s, &mut ring);
        around.extend(ring.iter().copied());
        around.sort_unstable();
        around.dedup();
        self.set_edge_flags(s, &ring);
        let mut changed = Vec::new();
        for &x in &around {
            let record = self.verts[x as usize];
            if !record.alive() || record.meta & (BOUNDARY | NON_MANIFOLD) == 0 {
                continue;
            }
            self.ring_into(x, &mut ring);
            self.set_edge_flags(x, &ring);
            if self.verts[x as usize].meta != record.meta {
                changed.push(x);
            }
        }
        self.refreshed = changed;
    }

    /// The distinct neighbours of `v` over its live faces, into `ring`.
    fn ring_into(&self, v: u32, ring: &mut Vec<u32>) {
        ring.clear();
        for k in self.incident(v) {
            let face = self.faces[self.refs[k] as usize];
            if face[0] == DEAD {
                continue;
            }
            for x in face {
                if x != v && !ring.contains(&x) {
                    ring.push(x);
                }
            }
        }
    }

    /// Sets [`BOUNDARY`] and [`NON_MANIFOLD`] on `v` from the face counts of its edges to
    /// `ring` (its neighbours).
    fn set_edge_flags(&mut self, v: u32, ring: &[u32]) {
        let mut flags = 0;
        for &x in ring {
            match self.edge_face_count(v, x) {
                1 => flags |= BOUNDARY,
                0 | 2 => {}
                _ => flags |= NON_MANIFOLD,
            }
        }
        let record = &mut self.verts[v as usize];
        record.meta = record.meta & !(BOUNDARY | NON_MANIFOLD) | flags;
    }

    /// The neighbours whose flags the last [`Self::collapse`] changed (besides its survivor).
    pub(crate) fn refreshed(&self) -> &[u32] {
        &self.refreshed
    }

    /// Whether `refs` has grown past [`refs_limit`] and wants [`Collapser::compact_refs`].
    pub(crate) fn refs_full(&self) -> bool {
        self.refs.len() > refs_limit(self.faces.len())
    }

    /// Rewrites `refs` with only the live faces of live vertices, into a buffer as large as
    /// the old one.
    pub(crate) fn compact_refs(&mut self) {
        let mut refs = Vec::with_capacity(self.refs.capacity());
        for v in 0..self.verts.len() {
            let range = self.incident(v as u32);
            let start = refs.len();
            refs.extend(
                self.refs[range]
                    .iter()
                    .copied()
                    .filter(|&f| self.faces[f as usize][0] != DEAD),
            );
            let len = refs.len() - start;
            self.verts[v].set_incident(start, len);
        }
        self.refs = refs;
    }

    /// Builds the output mesh and the vertex map.
    /// The quadrics of the vertices left, in the output's order (that of [`Self::finish`]).
    pub(crate) fn survivor_quadrics(&self) -> Vec<Quadric> {
        self.verts
            .iter()
            .zip(&self.quadrics)
            .filter(|(v, _)| v.alive())
            .map(|(_, &q)| q)
            .collect()
    }

    pub(crate) fn finish(self, stop_reason: StopReason) -> Result<Decimation> {
        let n = self.verts.len();
        let alive = |v: usize| self.verts[v].alive();
        let mut new_index = vec![u32::MAX; n];
        let mut vertices = Vec::new();
        for (v, index) in new_index.iter_mut().enumerate() {
            if alive(v) {
                *index = vertices.len() as u32;
                vertices.push(self.verts[v].position);
            }
        }
        let gather3 = |values: &Option<Vec<[f32; 3]>>| {
            values.as_ref().map(|x| {
                (0..n)
                    .filter(|&v| alive(v))
                    .map(|v| x[v])
                    .collect::<Vec<_>>()
            })
        };
        let triangles: Vec<[u32; 3]> = self
            .faces
            .iter()
            .filter(|f| f[0] != DEAD)
            .map(|f| f.map(|v| new_index[v as usize]))
            .collect();
        // Each welded vertex's surviving representative, memoised so the work stays linear.
        let mut root = vec![u32::MAX; n];
        for v in 0..n {
            let mut r = v;
            while !alive(r) && root[r] == u32::MAX {
                r = self.parent[r] as usize;
            }
            let found = if alive(r) { r as u32 } else { root[r] };
            let mut w = v;
            while !alive(w) && root[w] == u32::MAX {
                root[w] = found;
                w = self.parent[w] as usize;
            }
            root[v] = found;
        }
        let vertex_map = self
            .weld_map
            .iter()
            .map(|&w| new_index[root[w as usize] as usize])
            .collect();
        let mut out = TriMesh::new(vertices, triangles)?;
        if let Some(normals) = gather3(&self.normals) {
            out = out.with_normals(normals)?;
        }
        if let Some(uvs) = &self.uvs {
            out = out.with_uvs((0..n).filter(|&v| alive(v)).map(|v| uvs[v]).collect())?;
        }
        if let Some(colors) = gather3(&self.colors) {
            out = out.with_colors(colors)?;
        }
        Ok(Decimation {
            mesh: out,
            vertex_map,
            error: self.max_error,
            error_distance: self.max_error.sqrt(),
            max_cost: self.max_cost,
            welded: self.welded,
            stop_reason,
            input_faces: self.input_size.0,
            input_vertices: self.input_size.1,
            collapses: self.collapses,
        })
    }
}

/// The length of `refs` (incidence lists, appended to at every collapse) past which it is
/// compacted (between batches of collapses). `refs` is allocated with room for this and
/// [`REFS_SLACK`], so the collapse loop, which runs on a pool thread, does not reallocate it
/// (which would take fresh memory from that thread's allocator arena).
fn refs_limit(face_count: usize) -> usize {
    4 * face_count + 1024
}
