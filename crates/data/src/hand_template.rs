//! The procedural hand template: a quad cage built on a posed skeleton, refined by
//! Catmull–Clark into a smooth, fixed-topology, quad-dominant surface, then triangulated.
//!
//! Thesis ch. 3.3: Handy is learned from registered scans that share one template topology
//! with an open boundary at the wrist cut. Here the cage is a palm tube (16-vertex
//! cross-section, 4 rings, open at the wrist, with a transverse arch) capped at the knuckle
//! line by seven quads; the four finger quads and one radial palm side quad near the wrist
//! (thumb) are extruded along each digit's posed bone chain into square tubes with rounded
//! caps, so the topology is fixed by construction and every sample differs only in vertex
//! positions. Joint rings take the half rotation of their joint (a skinning weight of ½ at
//! cage level), and subdivision spreads it into smooth weights: phalanges rotate rigidly about
//! their joint axes with smooth blends at the joints; the wrist bends the palm the same way.
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
use crate::vec3::{
    M3, V3, add, axis_angle, column, cross, mul_m, mul_v, norm, normalize, rotation_fraction,
    scale, sub, to_f32, to_f64, transpose,
};

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
    /// Index of each digit's first cage vertex (thumb first).
    digit_start: [usize; 5],
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

/// Cage vertices per palm ring (the wrist ring comes first).
const PALM_RING_VERTICES: usize = 16;
/// Cage rings per digit (see [`digit_rings`]).
const RINGS_PER_DIGIT: usize = 6;

/// One cage ring of a digit seen as a cross-section: its centre, the unit direction of its
/// dorsal (nail) side, and its dorsal and palmar half-thicknesses.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DigitSection {
    pub centre: V3,
    pub dorsal: V3,
    pub dorsal_half: f64,
    pub palmar_half: f64,
}

impl DigitSection {
    /// A point on the limit surface's dorsal (`side = 1`) or palmar (`side = -1`) side: the
    /// cage corner midpoint pulled in to ¾ of its distance, where Catmull–Clark puts a
    /// square tube's surface.
    pub fn surface_point(&self, side: f64) -> V3 {
        let reach = if side > 0.0 {
            self.dorsal_half
        } else {
            self.palmar_half
        };
        add(self.centre, scale(self.dorsal, side * 0.75 * reach))
    }
}

/// The cage sections of every digit (thumb first), ring by ring from the base to the cap.
pub(crate) fn digit_sections(
    shape: &HandShape,
    pose: &HandPose,
) -> [[DigitSection; RINGS_PER_DIGIT]; 5] {
    let cage = build_cage(shape, pose);
    std::array::from_fn(|f| {
        std::array::from_fn(|r| {
            let at = |k: usize| cage.positions[cage.digit_start[f] + 4 * r + k];
            let dorsal_mid = scale(add(at(0), at(1)), 0.5);
            let palmar_mid = scale(add(at(2), at(3)), 0.5);
            let centre = scale(add(add(at(0), at(1)), add(at(2), at(3))), 0.25);
            DigitSection {
                centre,
                dorsal: normalize(sub(dorsal_mid, palmar_mid)),
                dorsal_half: norm(sub(dorsal_mid, centre)),
                palmar_half: norm(sub(palmar_mid, centre)),
            }
        })
    })
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
    let middle_x = 0.5 * (xs[4] + xs[5]);
    // Palm rows: (y, width scale, thickness scale, share of the transverse arch). The top
    // row (the finger webs) follows the knuckle line's arc, lowest at the little finger.
    let rows = [
        (0.0, 0.80, 0.80, 0.0),
        (0.15 * l, 0.92, 0.95, 0.35),
        (0.5 * l, 1.0, 1.0, 0.8),
        (l, 1.0, 0.80, 1.0),
    ];
    // Transverse (metacarpal) arch depth at the palm's edges; cupping deepens it.
    let arch = w * (0.04 + 0.08 * pose.cupping);
    let mut palm_rings = Vec::with_capacity(rows.len());
    for (k, &(y, ws, ts, arch_share)) in rows.iter().enumerate() {
        let mut idx = [0u32; PALM_RING_VERTICES];
        let point = |i: usize, dorsal: bool| {
            let u = xs[i] / (0.5 * w);
            let v = (xs[i] - middle_x) / (0.5 * w);
            let y = if k == rows.len() - 1 {
                y * (1.0 - 0.07 * v * v)
            } else {
                y
            };
            let lift = -arch * arch_share * u * u;
            let z = if dorsal {
                0.5 * t * ts * (1.0 - 0.25 * u * u)
            } else {
                -0.5 * t * ts * (1.0 - 0.15 * u * u)
            };
            [xs[i] * ws, y, z + lift]
        };
        for (i, slot) in idx.iter_mut().enumerate() {
            // Dorsal corners left to right, then palmar ones right to left.
            *slot = if i < 8 {
                cage.vertex(point(i, true))
            } else {
                cage.vertex(point(15 - i, false))
            };
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
        let corners = base.map(|v| cage.positions[v as usize]);
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
        cage.digit_start[finger] = cage.positions.len();
        cage.extrude(base, &rings);
    }
    // Thumb from the radial palm side near the wrist (rows 1-2), its metacarpal in the
    // thenar eminence: palmar of the palm's mid-plane, pointing out at 25° to the knuckle
    // line and bent up by `THUMB_REST_MCP` at its MCP, its pad facing the index; opposition
    // swings it out of the palm plane (palmar abduction) and turns the pad further towards
    // the fingers.
    let (a, b) = (palm_rings[thumb_row], palm_rings[thumb_row + 1]);
    let base = [a[7], a[8], b[8], b[7]];
    let corners = base.map(|v| cage.positions[v as usize]);
    let centre = scale(corners.iter().fold([0.0; 3], |acc, &p| add(acc, p)), 0.25);
    let lengths = shape.phalanges[0];
    let frame = thumb_base_frame(pose);
    let joint = add(centre, [-0.25 * lengths[0], 0.0, -0.15 * t]);
    let rings = digit_rings(
        joint,
        &frame,
        [1.1 * lengths[0], lengths[1], lengths[2]],
        [
            pose.flexion[0][0],
            pose.flexion[0][1] + THUMB_REST_MCP.to_radians(),
            pose.flexion[0][2],
        ],
        1.1 * shape.half_width[0],
        shape.taper[0],
        0.6 * shape.knuckle,
        shape.fingertip_pad,
    );
    // The thenar skin around the thumb's base follows its metacarpal's rotation away from
    // rest (skinning weights ½ on the base quad, as at the other joints, ¼ on its palmar and
    // dorsal neighbours), so that the metacarpal does not cut the palm.
    let rest_metacarpal = thumb_base_frame(&HandPose::rest());
    let metacarpal = flex(&frame, pose.flexion[0][0]);
    let rotation = mul_m(&metacarpal, &transpose(&rest_metacarpal));
    let (half, quarter) = (
        rotation_fraction(&rotation, 0.5),
        rotation_fraction(&rotation, 0.25),
    );
    let thenar = [a[9], b[9], a[6], b[6]];
    for (vertices, share) in [(&base, &half), (&thenar, &quarter)] {
        for &v in vertices {
            let p = &mut cage.positions[v as usize];
            *p = add(joint, mul_v(share, sub(*p, joint)));
        }
    }
    cage.digit_start[0] = cage.positions.len();
    cage.extrude(base, &rings);
    bend_wrist(&mut cage.positions, pose, l);
    cage
}

/// Flexion of the thumb's MCP in the rest pose, degrees: the metacarpal leaves the palm's
/// side nearly sideways (a steeper tube would cut the palm), the phalanges point up.
const THUMB_REST_MCP: f64 = 20.0;

/// The thumb's base frame (columns: flexion axis, direction, nail side) in `pose`.
fn thumb_base_frame(pose: &HandPose) -> M3 {
    let phi = 25f64.to_radians() - pose.spread[0];
    let direction = [phi.cos(), phi.sin(), 0.0];
    // In the palm plane, perpendicular to the thumb, away from the fingers.
    let outward = [phi.sin(), -phi.cos(), 0.0];
    // At rest the thumb is pronated a quarter turn against the fingers: its nail faces away
    // from them, its flexion axis is the palm normal (the base quad's corners line up).
    let rest = columns(cross(direction, outward), direction, outward);
    let abducted = mul_m(&axis_angle(outward, -pose.opposition), &rest);
    let pronation = axis_angle(column(&abducted, 1), -0.6 * pose.opposition);
    mul_m(&pronation, &abducted)
}

/// The matrix with columns `x`, `y`, `z`.
fn columns(x: V3, y: V3, z: V3) -> M3 {
    [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
}

/// Wrist flexion and deviation about a pivot just above the wrist cut: the cut ring stays,
/// the next palm ring takes half the rotation (a smooth crease), everything beyond all of it.
fn bend_wrist(positions: &mut [V3], pose: &HandPose, palm_length: f64) {
    let [flexion, deviation] = pose.wrist;
    if flexion == 0.0 && deviation == 0.0 {
        return;
    }
    let rotation = |share: f64| {
        mul_m(
            &axis_angle([0.0, 0.0, 1.0], share * deviation),
            &axis_angle([1.0, 0.0, 0.0], -share * flexion),
        )
    };
    let (half, full) = (rotation(0.5), rotation(1.0));
    let pivot = [0.0, 0.06 * palm_length, 0.0];
    for (i, p) in positions.iter_mut().enumerate().skip(PALM_RING_VERTICES) {
        let r = if i < 2 * PALM_RING_VERTICES {
            &half
        } else {
            &full
        };
        *p = add(pivot, mul_v(r, sub(*p, pivot)));
    }
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
