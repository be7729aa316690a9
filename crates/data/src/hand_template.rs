//! The procedural hand template: a quad cage built on a posed skeleton, refined by
//! Catmull–Clark into a smooth, fixed-topology, quad-dominant surface, then triangulated.
//!
//! Thesis ch. 3.3: Handy is learned from registered scans that share one template topology
//! with an open boundary at the wrist cut. Here the cage is a palm tube (16-vertex
//! cross-section, 4 rings, open at the wrist) capped at the knuckle line by seven quads; the
//! four finger quads and one palm side quad (thumb) are extruded along each digit's posed bone
//! chain into square tubes with rounded caps, so the topology is fixed by construction and
//! every sample differs only in vertex positions. Joint rings take the half rotation of their
//! joint (a skinning weight of ½ at cage level), and subdivision spreads it into smooth
//! weights: phalanges rotate rigidly about their joint axes with smooth blends at the joints.
//!
//! # Conventions
//! - Millimetres; wrist centre at the origin, fingers along +y, back of the hand towards +z,
//!   thumb towards +x (a right hand seen from its back).
//! - Triangles are counter-clockwise seen from outside. The only boundary is the wrist loop.

use meshgnn_geometry::{TriMesh, vertex_normals};
use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::catmull_clark::{QuadSubdivision, catmull_clark};
use crate::error::{Result, invalid};
use crate::hand_pose::HandPose;
use crate::hand_shape::HandShape;
use crate::vec3::{M3, V3, add, axis_angle, column, mul_m, normalize, scale, sub, to_f32, to_f64};

/// Default number of Catmull–Clark levels (2 833 vertices): the template of the bundled
/// Handy++ model, so `synth hands` and `handy` work together out of the box.
pub const DEFAULT_HAND_SUBDIVISIONS: u32 = 2;

/// A hand template of fixed topology at a given resolution.
#[derive(Debug, Clone)]
pub struct HandTemplate {
    cage_quads: Vec<[u32; 4]>,
    cage_vertex_count: usize,
    levels: Vec<QuadSubdivision>,
    triangles: Vec<[u32; 3]>,
    rest: Vec<V3>,
}

/// A quad cage under construction.
#[derive(Default)]
struct Cage {
    positions: Vec<V3>,
    quads: Vec<[u32; 4]>,
}

impl Cage {
    fn vertex(&mut self, p: V3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// Extrudes the base quad `base` (counter-clockwise seen from the extrusion side) through
    /// `rings` (each 4 positions in the base's corner order) and closes the end with a cap.
    fn extrude(&mut self, base: [u32; 4], rings: &[[V3; 4]]) {
        let mut prev = base;
        for ring in rings {
            let next = ring.map(|p| self.vertex(p));
            for i in 0..4 {
                let j = (i + 1) % 4;
                self.quads.push([prev[i], prev[j], next[j], next[i]]);
            }
            prev = next;
        }
        self.quads.push(prev);
    }
}

/// Rotation about the local x axis of `frame` by `-angle` (flexion towards local −z).
fn flex(frame: &M3, angle: f64) -> M3 {
    mul_m(frame, &axis_angle([1.0, 0.0, 0.0], -angle))
}

/// The four ring corners of a digit cross-section centred at `centre` in `frame`: half-width
/// `hw` along local x, dorsal and palmar half-thickness along local ±z.
fn ring(centre: V3, frame: &M3, hw: f64, dorsal: f64, palmar: f64) -> [V3; 4] {
    let (x, z) = (column(frame, 0), column(frame, 2));
    let at = |u: f64, v: f64| add(centre, add(scale(x, u), scale(z, v)));
    [
        at(-hw, dorsal),
        at(hw, dorsal),
        at(hw, -palmar),
        at(-hw, -palmar),
    ]
}

/// The six cage rings of one digit whose base joint is at `joint` with frame `base_frame`.
#[allow(clippy::too_many_arguments)]
fn digit_rings(
    joint: V3,
    base_frame: &M3,
    lengths: [f64; 3],
    flexion: [f64; 3],
    half_width: f64,
    taper: f64,
    knuckle: f64,
    pad: f64,
) -> Vec<[V3; 4]> {
    let r1 = flex(base_frame, flexion[0]);
    let r2 = flex(&r1, flexion[1]);
    let r3 = flex(&r2, flexion[2]);
    let h2 = flex(&r1, 0.5 * flexion[1]);
    let h3 = flex(&r2, 0.5 * flexion[2]);
    let along = |frame: &M3, from: V3, t: f64| add(from, scale(column(frame, 1), t));
    let j2 = along(&r1, joint, lengths[0]);
    let j3 = along(&r2, j2, lengths[1]);
    let total: f64 = lengths.iter().sum();
    let width = |s: f64| 1.15 * half_width * (1.0 - (1.0 - taper) * (s / total).clamp(0.0, 1.0));
    let ring_at = |centre: V3, frame: &M3, s: f64, extra_dorsal: f64, extra_palmar: f64| {
        let hw = width(s);
        ring(
            centre,
            frame,
            hw,
            0.85 * hw + extra_dorsal,
            0.85 * hw + extra_palmar,
        )
    };
    let s2 = lengths[0];
    let s3 = lengths[0] + lengths[1];
    let tip_hw = width(total);
    vec![
        ring_at(
            along(&r1, joint, 0.5 * lengths[0]),
            &r1,
            0.5 * lengths[0],
            0.0,
            0.0,
        ),
        ring_at(j2, &h2, s2, knuckle, 0.0),
        ring_at(
            along(&r2, j2, 0.5 * lengths[1]),
            &r2,
            s2 + 0.5 * lengths[1],
            0.0,
            0.0,
        ),
        ring_at(j3, &h3, s3, 0.6 * knuckle, 0.0),
        ring_at(
            along(&r3, j3, 0.7 * lengths[2]),
            &r3,
            s3 + 0.7 * lengths[2],
            0.0,
            pad,
        ),
        ring(
            along(&r3, j3, lengths[2] - 0.25 * tip_hw),
            &r3,
            0.55 * tip_hw,
            0.45 * tip_hw,
            0.5 * tip_hw + 0.5 * pad,
        ),
    ]
}

/// The cage of `shape` in `pose` (same topology for every input).
fn build_cage(shape: &HandShape, pose: &HandPose) -> Cage {
    let mut cage = Cage::default();
    let (w, l, t) = (shape.palm_width, shape.palm_length, shape.palm_thickness);
    // Column widths across the knuckle line: little, web, ring, web, middle, web, index.
    let finger_cols = [4usize, 3, 2, 1].map(|f| 2.0 * shape.half_width[f]);
    let fingers: f64 = finger_cols.iter().sum();
    let squeeze = if fingers > 0.88 * w {
        0.88 * w / fingers
    } else {
        1.0
    };
    let web = (w - squeeze * fingers) / 3.0;
    let mut xs = [0.0f64; 8];
    xs[0] = -0.5 * w;
    for c in 0..7 {
        let width = if c % 2 == 0 {
            squeeze * finger_cols[c / 2]
        } else {
            web
        };
        xs[c + 1] = xs[c] + width;
    }
    // Palm rows: (y, width scale, thickness scale).
    let rows = [
        (0.0, 0.80, 0.80),
        (0.2 * l, 0.92, 0.95),
        (0.55 * l, 1.0, 1.0),
        (l, 1.0, 0.80),
    ];
    let mut palm_rings = Vec::with_capacity(rows.len());
    for &(y, ws, ts) in &rows {
        let mut idx = [0u32; 16];
        for i in 0..8 {
            let x = xs[i] * ws;
            let u = xs[i] / (0.5 * w);
            let dorsal = 0.5 * t * ts * (1.0 - 0.25 * u * u);
            idx[i] = cage.vertex([x, y, dorsal]);
        }
        for j in 0..8 {
            let i = 7 - j;
            let x = xs[i] * ws;
            let u = xs[i] / (0.5 * w);
            let palmar = 0.5 * t * ts * (1.0 - 0.15 * u * u);
            idx[8 + j] = cage.vertex([x, y, -palmar]);
        }
        palm_rings.push(idx);
    }
    let thumb_row = 1;
    for k in 0..rows.len() - 1 {
        for i in 0..16 {
            if k == thumb_row && i == 7 {
                continue;
            }
            let j = (i + 1) % 16;
            let (a, b) = (palm_rings[k], palm_rings[k + 1]);
            cage.quads.push([a[i], a[j], b[j], b[i]]);
        }
    }
    let top = palm_rings[rows.len() - 1];
    // Knuckle-line cap: webs stay, finger columns are extruded.
    let rest_fan = [0.0, 3.0f64, 0.0, 3.0, 7.0].map(f64::to_radians);
    for c in 0..7 {
        let base = [top[c], top[c + 1], top[14 - c], top[15 - c]];
        if c % 2 == 1 {
            cage.quads.push(base);
            continue;
        }
        let finger = [4usize, 3, 2, 1][c / 2];
        let corners = base.map(|v| cage.positions.get(v as usize).copied().unwrap_or_default());
        let centre = scale(corners.iter().fold([0.0; 3], |acc, &p| add(acc, p)), 0.25);
        // Index (+x side) spreads towards +x: a negative rotation about +z.
        let side = if finger <= 2 { -1.0 } else { 1.0 };
        let spread = axis_angle(
            [0.0, 0.0, 1.0],
            side * (rest_fan[finger] + pose.spread[finger]),
        );
        let lengths = shape.phalanges[finger];
        let joint = sub(centre, [0.0, 0.22 * lengths[0], 0.0]);
        let rings = digit_rings(
            joint,
            &spread,
            [1.22 * lengths[0], lengths[1], lengths[2]],
            pose.flexion[finger],
            shape.half_width[finger],
            shape.taper[finger],
            shape.knuckle,
            shape.fingertip_pad,
        );
        cage.extrude(base, &rings);
    }
    // Thumb from the +x palm side between rows 1 and 2.
    let (a, b) = (palm_rings[thumb_row], palm_rings[thumb_row + 1]);
    let base = [a[7], a[8], b[8], b[7]];
    let corners = base.map(|v| cage.positions.get(v as usize).copied().unwrap_or_default());
    let centre = scale(corners.iter().fold([0.0; 3], |acc, &p| add(acc, p)), 0.25);
    // Local x → −z (palmar), local y → +x (out of the palm side), local z → −y (wristwards).
    let side_frame: M3 = [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]];
    let yaw = axis_angle([0.0, 0.0, 1.0], 30f64.to_radians() - pose.spread[0]);
    let oppose = axis_angle([0.0, 0.0, 1.0], -pose.opposition);
    let frame = mul_m(&mul_m(&yaw, &side_frame), &oppose);
    let lengths = shape.phalanges[0];
    let joint = sub(centre, [0.1 * lengths[0], 0.0, 0.0]);
    let rings = digit_rings(
        joint,
        &frame,
        [0.95 * lengths[0], lengths[1], lengths[2]],
        pose.flexion[0],
        1.1 * shape.half_width[0],
        shape.taper[0],
        0.6 * shape.knuckle,
        shape.fingertip_pad,
    );
    cage.extrude(base, &rings);
    cage
}

impl HandTemplate {
    /// The template refined by `subdivisions` Catmull–Clark levels, `1..=4`
    /// (1: 717 vertices, 2 (default): 2 833, 3: 11 265, 4: 44 929).
    ///
    /// ```
    /// use meshgnn_data::HandTemplate;
    /// let t = HandTemplate::new(1)?;
    /// assert_eq!(t.vertex_count(), 717);
    /// assert!(HandTemplate::new(0).is_err());
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn new(subdivisions: u32) -> Result<Self> {
        if !(1..=4).contains(&subdivisions) {
            return Err(invalid("subdivisions", subdivisions, "must be in 1..=4"));
        }
        let cage = build_cage(&HandShape::adult(), &HandPose::rest());
        let mut levels = Vec::new();
        let mut quads = cage.quads.clone();
        let mut count = cage.positions.len();
        for _ in 0..subdivisions {
            let level = catmull_clark(&quads, count)?;
            quads = level.quads().to_vec();
            count = level.vertex_count();
            levels.push(level);
        }
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let mut template = Self {
            cage_vertex_count: cage.positions.len(),
            cage_quads: cage.quads,
            levels,
            triangles,
            rest: Vec::new(),
        };
        template.rest = template.refine(cage.positions)?;
        Ok(template)
    }

    /// Number of vertices `#V` of every generated hand.
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// The shared triangles `#F×3` (counter-clockwise seen from outside).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The coarse cage quads `#Q×4` (the quad-dominant control mesh).
    pub fn cage_quads(&self) -> &[[u32; 4]] {
        &self.cage_quads
    }

    /// The mean adult hand in the rest pose, `#V×3` (millimetres).
    pub fn rest_vertices(&self) -> Vec<[f32; 3]> {
        self.rest.iter().copied().map(to_f32).collect()
    }

    fn refine(&self, mut positions: Vec<V3>) -> Result<Vec<V3>> {
        for level in &self.levels {
            positions = level.apply(&positions)?;
        }
        Ok(positions)
    }

    /// The vertices `#V×3` of `shape` in `pose`: the posed cage refined, plus the subject's
    /// smooth surface noise along the normals (a sum of 8 random plane waves of wavelength
    /// 25-60 mm over the template's rest positions, RMS `shape.noise_amplitude`).
    ///
    /// ```
    /// use meshgnn_data::{HandPose, HandShape, HandTemplate};
    /// let t = HandTemplate::new(1)?;
    /// let v = t.generate_vertices(&HandShape::adult(), &HandPose::rest())?;
    /// let top = v.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
    /// assert!(top > 150.0 && top < 195.0); // middle fingertip of a 190 mm hand
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn generate_vertices(&self, shape: &HandShape, pose: &HandPose) -> Result<Vec<[f32; 3]>> {
        let cage = build_cage(shape, pose);
        if cage.positions.len() != self.cage_vertex_count {
            return Err(invalid(
                "shape",
                cage.positions.len(),
                "cage vertex count differs from the template",
            ));
        }
        let fine = self.refine(cage.positions)?;
        let mut out: Vec<[f32; 3]> = fine.iter().copied().map(to_f32).collect();
        if shape.noise_amplitude > 0.0 {
            let mesh = TriMesh::new(out.clone(), self.triangles.clone())?;
            let normals = vertex_normals(&mesh);
            let mut rng = StdRng::seed_from_u64(shape.noise_seed);
            let waves: Vec<(V3, f64)> = (0..8)
                .map(|_| {
                    let dir = normalize([
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    ]);
                    let wavelength: f64 = rng.random_range(25.0..60.0);
                    let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                    (scale(dir, std::f64::consts::TAU / wavelength), phase)
                })
                .collect();
            // RMS of a sum of 8 unit sines is 2; scale to the requested amplitude.
            let amp = shape.noise_amplitude / 2.0;
            for ((p, n), r) in out.iter_mut().zip(&normals).zip(&self.rest) {
                let h: f64 = waves
                    .iter()
                    .map(|(k, ph)| (k[0] * r[0] + k[1] * r[1] + k[2] * r[2] + ph).sin())
                    .sum();
                // Fade out towards the wrist cut so the boundary stays on its plane.
                let fade = crate::face_template::smoothstep(0.0, 15.0, r[1]);
                *p = to_f32(add(to_f64(*p), scale(to_f64(*n), fade * amp * h)));
            }
        }
        Ok(out)
    }

    /// The hand mesh of `shape` in `pose` (see [`HandTemplate::generate_vertices`]).
    pub fn generate(&self, shape: &HandShape, pose: &HandPose) -> Result<TriMesh> {
        Ok(TriMesh::new(
            self.generate_vertices(shape, pose)?,
            self.triangles.clone(),
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{boundary_loops, mesh_report};

    #[test]
    fn template_is_manifold_with_one_wrist_boundary() {
        for s in 1..=2 {
            let t = HandTemplate::new(s).unwrap();
            let mesh = t.generate(&HandShape::adult(), &HandPose::rest()).unwrap();
            let report = mesh_report(&mesh);
            assert!(report.edge_manifold && report.vertex_manifold, "{report:?}");
            let loops = boundary_loops(&mesh);
            assert_eq!(loops.len(), 1);
            // The loop lies on the wrist plane y = 0.
            for &v in &loops[0] {
                assert!(mesh.vertices()[v as usize][1].abs() < 1e-4);
            }
            assert_eq!(report.components, 1);
        }
    }

    #[test]
    fn flexion_moves_fingertip_towards_the_palm() {
        let t = HandTemplate::new(1).unwrap();
        let shape = HandShape::adult();
        let rest = t.generate_vertices(&shape, &HandPose::rest()).unwrap();
        let mut pose = HandPose::rest();
        pose.flexion[2] = [0.8, 0.9, 0.6];
        let bent = t.generate_vertices(&shape, &pose).unwrap();
        let tip = |v: &[[f32; 3]]| v.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
        let low = |v: &[[f32; 3]]| v.iter().map(|p| p[2]).fold(f32::MAX, f32::min);
        assert!(tip(&bent) <= tip(&rest));
        assert!(low(&bent) < low(&rest) - 10.0);
    }
}
