//! Procedural shape families for the simplification set, each a random signed distance
//! function meshed by [`crate::marching_tetrahedra`], and their family-disjoint split:
//!
//! | family | split | description |
//! |---|---|---|
//! | `boxes` | train | CAD blocks: bevelled boxes with drilled holes and bosses |
//! | `gears` | train | spur gears: teeth, bore, hub |
//! | `creatures-a` | train | quadrupeds: body, neck, head, four legs, tail, bumps (smooth-min) |
//! | `fandisk` | test | fandisk-like blends: a block cut by a cylinder and planes, smooth and sharp edges |
//! | `creatures-b` | test | upright bipeds with arms and antennae |
//!
//! Test families never appear in training: the zero-shot setting of thesis ch. 5.5 and 6.5.

use meshgnn_geometry::TriMesh;
use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;

use super::marching_tetrahedra::marching_tetrahedra;
use super::sdf::{capsule, cylinder_z, ellipsoid, round_box, smax, smin, sphere};
use crate::error::{Result, invalid};
use crate::vec3::V3;

/// A procedural shape family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ShapeFamily {
    /// Bevelled boxes with holes and bosses (train).
    Boxes,
    /// Spur gears (train).
    Gears,
    /// Quadruped creatures (train).
    CreaturesA,
    /// Fandisk-like blended solids (test).
    Fandisk,
    /// Biped creatures (test).
    CreaturesB,
}

impl ShapeFamily {
    /// All families.
    pub const ALL: [ShapeFamily; 5] = [
        ShapeFamily::Boxes,
        ShapeFamily::Gears,
        ShapeFamily::CreaturesA,
        ShapeFamily::Fandisk,
        ShapeFamily::CreaturesB,
    ];

    /// File-name friendly name.
    pub fn name(self) -> &'static str {
        match self {
            ShapeFamily::Boxes => "boxes",
            ShapeFamily::Gears => "gears",
            ShapeFamily::CreaturesA => "creatures-a",
            ShapeFamily::Fandisk => "fandisk",
            ShapeFamily::CreaturesB => "creatures-b",
        }
    }

    /// `train` or `test` (family-disjoint).
    pub fn split(self) -> &'static str {
        match self {
            ShapeFamily::Fandisk | ShapeFamily::CreaturesB => "test",
            _ => "train",
        }
    }
}

type Sdf = Box<dyn Fn(V3) -> f64 + Sync + Send>;

fn boxes(rng: &mut StdRng) -> Sdf {
    let b = [
        rng.random_range(0.6..0.9),
        rng.random_range(0.4..0.7),
        rng.random_range(0.25..0.45),
    ];
    let bevel = rng.random_range(0.03..0.12);
    let holes: Vec<(f64, f64, f64)> = (0..rng.random_range(1..4))
        .map(|_| {
            (
                rng.random_range(-0.6..0.6) * b[0],
                rng.random_range(-0.6..0.6) * b[1],
                rng.random_range(0.06..0.15),
            )
        })
        .collect();
    let bosses: Vec<(f64, f64, f64, f64)> = (0..rng.random_range(0..3))
        .map(|_| {
            (
                rng.random_range(-0.6..0.6) * b[0],
                rng.random_range(-0.6..0.6) * b[1],
                rng.random_range(0.08..0.18),
                rng.random_range(0.08..0.2),
            )
        })
        .collect();
    Box::new(move |p| {
        let mut d = round_box(p, [0.0; 3], b, bevel);
        for &(x, y, r, h) in &bosses {
            d = d.min(cylinder_z(p, [x, y, b[2] + 0.5 * h], r, 0.5 * h + 0.02));
        }
        for &(x, y, r) in &holes {
            d = d.max(-cylinder_z(p, [x, y, 0.0], r, 2.0));
        }
        d
    })
}

fn gears(rng: &mut StdRng) -> Sdf {
    let teeth = rng.random_range(8..24) as f64;
    let radius = rng.random_range(0.6..0.85);
    let depth = rng.random_range(0.08..0.14);
    let thick = rng.random_range(0.12..0.25);
    let bore = rng.random_range(0.1..0.25);
    let hub = bore + rng.random_range(0.08..0.15);
    Box::new(move |p: V3| {
        let r = p[0].hypot(p[1]);
        let a = p[1].atan2(p[0]);
        let wave = (teeth * a).cos();
        let tooth = (wave * 2.5).clamp(-1.0, 1.0);
        let outer = r - (radius + 0.5 * depth * tooth);
        let gear = outer.max(p[2].abs() - thick);
        let hub_d = (r - hub).max(p[2].abs() - thick - 0.1);
        gear.min(hub_d).max(bore - r)
    })
}

fn fandisk(rng: &mut StdRng) -> Sdf {
    let b = [
        rng.random_range(0.6..0.8),
        rng.random_range(0.45..0.6),
        rng.random_range(0.35..0.5),
    ];
    let cyl_r = rng.random_range(0.35..0.55);
    let tilt: f64 = rng.random_range(0.3..0.7);
    let k = rng.random_range(0.05..0.15);
    Box::new(move |p: V3| {
        let block = round_box(p, [0.0; 3], b, 0.02);
        // A cylinder along x bulging from the top, blended smoothly.
        let bulge = (p[1].hypot(p[2] - b[2] * 0.6) - cyl_r).max(p[0].abs() - 0.8 * b[0]);
        let body = smin(block, bulge, k);
        // A sharp slanted plane cut and a smooth concave groove.
        let cut = (p[0] * tilt + p[2]) / (1.0 + tilt * tilt).sqrt() - 0.75 * b[2];
        let groove = -(p[0].hypot(p[2] + b[2]) - 0.35);
        smax(body.max(cut), groove, 0.5 * k)
    })
}

fn creature(rng: &mut StdRng, biped: bool) -> Sdf {
    let body_r = [
        rng.random_range(0.45..0.6),
        rng.random_range(0.22..0.3),
        rng.random_range(0.25..0.32),
    ];
    let k = rng.random_range(0.08..0.15);
    let leg_r = rng.random_range(0.06..0.1);
    let head_r = rng.random_range(0.15..0.22);
    let bumps: Vec<(V3, f64)> = (0..rng.random_range(3..9))
        .map(|_| {
            let t: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let u: f64 = rng.random_range(-0.8..0.8);
            let s = (1.0 - u * u).sqrt();
            (
                [
                    body_r[0] * s * t.cos(),
                    body_r[1] * u,
                    body_r[2] * s * t.sin(),
                ],
                rng.random_range(0.04..0.09),
            )
        })
        .collect();
    let spread = rng.random_range(0.0..0.25);
    let lift = rng.random_range(-0.1..0.15);
    Box::new(move |p: V3| {
        if biped {
            // Upright: body along y, shifted down to fit the meshing box.
            let p = [p[0], p[1] + 0.12, p[2]];
            let body = ellipsoid(p, [0.0, 0.1, 0.0], [body_r[1] * 1.3, body_r[0], body_r[2]]);
            let head = sphere(p, [0.0, 0.1 + body_r[0] + head_r * 0.8, 0.0], head_r);
            let mut d = smin(body, head, k);
            for s in [-1.0, 1.0] {
                let hip = [s * 0.12, -0.25, 0.0];
                d = smin(
                    d,
                    capsule(p, hip, [s * (0.15 + spread), -0.9, 0.05], leg_r),
                    k,
                );
                let shoulder = [s * body_r[1] * 1.1, 0.35, 0.0];
                d = smin(
                    d,
                    capsule(p, shoulder, [s * 0.6, 0.1 + lift, 0.15], 0.8 * leg_r),
                    k,
                );
                let top = [0.0, 0.1 + body_r[0] + head_r * 1.5, 0.0];
                d = smin(
                    d,
                    capsule(p, top, [s * 0.15, top[1] + 0.2, 0.0], 0.025),
                    0.03,
                );
            }
            for &(c, r) in &bumps {
                d = smin(d, sphere(p, [c[1], c[0] + 0.1, c[2]], r), 0.05);
            }
            d
        } else {
            let body = ellipsoid(p, [0.0; 3], body_r);
            let head_c = [body_r[0] + head_r * 1.2, body_r[1] + lift + 0.15, 0.0];
            let neck = capsule(p, [body_r[0] * 0.7, 0.05, 0.0], head_c, 0.6 * head_r);
            let mut d = smin(smin(body, neck, k), sphere(p, head_c, head_r), k);
            for (sx, sz) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let hip = [sx * body_r[0] * 0.6, -0.05, sz * body_r[2] * 0.5];
                let foot = [
                    hip[0] + sx * spread * 0.5,
                    -0.75,
                    hip[2] + sz * spread * 0.4,
                ];
                d = smin(d, capsule(p, hip, foot, leg_r), k);
            }
            let tail = capsule(
                p,
                [-body_r[0] * 0.8, 0.0, 0.0],
                [-body_r[0] - 0.35, 0.15 + lift, 0.0],
                0.05,
            );
            d = smin(d, tail, k);
            for &(c, r) in &bumps {
                d = smin(d, sphere(p, c, r), 0.05);
            }
            d
        }
    })
}

/// Shape `index` of `family`, meshed at `resolution` grid cells along the longest side of the
/// box `[-1.2, 1.2]³` (64: ≈ 15-40k faces; 128: ≈ 60-160k faces). Deterministic from `seed`.
///
/// ```
/// use meshgnn_data::{ShapeFamily, shape_mesh};
/// use meshgnn_geometry::mesh_report;
/// let m = shape_mesh(ShapeFamily::Gears, 3, 48)?;
/// assert!(mesh_report(&m).watertight);
/// assert_eq!(m, shape_mesh(ShapeFamily::Gears, 3, 48)?);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn shape_mesh(family: ShapeFamily, seed: u64, resolution: usize) -> Result<TriMesh> {
    let mut rng = StdRng::seed_from_u64(seed);
    let sdf = match family {
        ShapeFamily::Boxes => boxes(&mut rng),
        ShapeFamily::Gears => gears(&mut rng),
        ShapeFamily::CreaturesA => creature(&mut rng, false),
        ShapeFamily::Fandisk => fandisk(&mut rng),
        ShapeFamily::CreaturesB => creature(&mut rng, true),
    };
    let mesh = marching_tetrahedra(&*sdf, [-1.2; 3], [1.2; 3], resolution)?;
    if mesh.face_count() == 0 {
        return Err(invalid("seed", seed, "the generated shape is empty"));
    }
    Ok(mesh)
}
