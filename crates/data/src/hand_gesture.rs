//! The gestures people show to hand scanners — flat, spread, relaxed, fist, pinch, point and
//! thumb opposition — as poses of a given hand, and a random pose drawn around them.
//!
//! Thesis ch. 3.3-3.4: the registered scans span the articulations of real hands, which is
//! what makes the space non-linear. Fingers follow the natural coupling of the distal joint to
//! the middle one (DIP ≈ ⅔ PIP). In the contact gestures the thumb is placed on its target
//! (the index pad in a pinch, the curled index and middle fingers in a fist, the middle
//! finger in a point, the middle fingertip in opposition) by solving for its five angles on
//! this hand's own skeleton, so children's and adults' thumbs both land where they should.

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::hand_pose::{HandPose, OPPOSITION_DEG, SPREAD_DEG, THUMB_FLEXION_DEG};
use crate::hand_shape::HandShape;
use crate::hand_template::{DigitSection, digit_sections};
use crate::vec3::{V3, add, dot, norm, normalize, scale, sub};

/// A hand gesture (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HandGesture {
    /// All joints straight, fingers together.
    Flat,
    /// Fingers and thumb spread apart, slightly hyper-extended.
    Spread,
    /// The resting hand: fingers a little curled, more towards the little finger.
    Relaxed,
    /// Fingers curled into the palm, the thumb across the index and middle fingers.
    Fist,
    /// The thumb's pad on the index fingertip, the other fingers loosely curled.
    Pinch,
    /// The index straight, the other fingers in a fist, the thumb on the middle finger.
    Point,
    /// The thumb opposed to the middle finger: pad to pad.
    Opposition,
}

/// Gap in millimetres left between the thumb and its target in the contact gestures.
const CONTACT_GAP: f64 = 1.0;

/// Where the thumb's pad goes: a surface point and the outward normal there.
struct ThumbTarget {
    point: V3,
    normal: V3,
}

impl HandGesture {
    /// Every gesture, in the order of [`HandGesture::name`]'s documentation.
    pub const ALL: [Self; 7] = [
        Self::Flat,
        Self::Spread,
        Self::Relaxed,
        Self::Fist,
        Self::Pinch,
        Self::Point,
        Self::Opposition,
    ];

    /// Lower-case name: `flat`, `spread`, `relaxed`, `fist`, `pinch`, `point`, `opposition`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Flat => "flat",
            Self::Spread => "spread",
            Self::Relaxed => "relaxed",
            Self::Fist => "fist",
            Self::Pinch => "pinch",
            Self::Point => "point",
            Self::Opposition => "opposition",
        }
    }

    /// The gesture at full strength for `shape` (the wrist straight).
    ///
    /// ```
    /// use meshgnn_data::{HandGesture, HandShape};
    /// let fist = HandGesture::Fist.pose(&HandShape::adult());
    /// assert!(fist.in_range());
    /// assert!(fist.flexion[2][1] > 1.5); // middle finger's PIP beyond 85°
    /// ```
    pub fn pose(self, shape: &HandShape) -> HandPose {
        let mut pose = self.finger_pose();
        place_thumb(self, shape, &mut pose);
        pose
    }

    /// The fingers (index to little) and cupping of the gesture; the thumb at a neutral start.
    fn finger_pose(self) -> HandPose {
        // [MCP, PIP] per finger, index to little, in degrees; DIP follows PIP.
        let (curl, spread, cupping): ([[f64; 2]; 4], f64, f64) = match self {
            Self::Flat => ([[0.0, 0.0]; 4], 0.0, 0.0),
            Self::Spread => ([[-10.0, 0.0]; 4], 1.0, 0.0),
            Self::Relaxed => (
                [[15.0, 25.0], [20.0, 30.0], [25.0, 35.0], [30.0, 40.0]],
                0.2,
                0.3,
            ),
            Self::Fist => ([[85.0, 100.0]; 4], 0.0, 1.0),
            Self::Pinch => (
                [[50.0, 60.0], [40.0, 55.0], [45.0, 60.0], [50.0, 65.0]],
                0.0,
                0.6,
            ),
            Self::Point => (
                [[0.0, 0.0], [85.0, 100.0], [85.0, 100.0], [85.0, 100.0]],
                0.0,
                0.8,
            ),
            Self::Opposition => (
                [[15.0, 20.0], [65.0, 65.0], [45.0, 55.0], [45.0, 55.0]],
                0.0,
                1.0,
            ),
        };
        let mut pose = HandPose::rest();
        for (f, [mcp, pip]) in curl.into_iter().enumerate() {
            pose.flexion[f + 1] = [mcp, pip, coupled_dip(pip)].map(f64::to_radians);
            pose.spread[f + 1] = spread * SPREAD_DEG[f + 1][1].to_radians();
        }
        pose.cupping = cupping;
        match self {
            Self::Spread => pose.spread[0] = SPREAD_DEG[0][1].to_radians(),
            Self::Relaxed => {
                pose.opposition = 20f64.to_radians();
                pose.flexion[0] = [5.0, 10.0, 15.0].map(f64::to_radians);
            }
            _ => {}
        }
        pose
    }

    /// True for the gestures whose thumb has no contact target.
    fn thumb_free(self) -> bool {
        matches!(self, Self::Flat | Self::Spread | Self::Relaxed)
    }

    /// Where the thumb must go in this gesture, or `None` when it is free.
    fn thumb_target(self, sections: &[[DigitSection; 6]; 5]) -> Option<ThumbTarget> {
        let pad = |f: usize| {
            let s = &sections[f][4];
            ThumbTarget {
                point: s.surface_point(-1.0),
                normal: scale(s.dorsal, -1.0),
            }
        };
        // The middle of the middle phalanx of a curled finger, on its nail side.
        let back = |f: usize| {
            let s = &sections[f][2];
            ThumbTarget {
                point: s.surface_point(1.0),
                normal: s.dorsal,
            }
        };
        match self {
            Self::Flat | Self::Spread | Self::Relaxed => None,
            Self::Pinch => Some(pad(1)),
            Self::Opposition => Some(pad(2)),
            Self::Point => Some(back(2)),
            Self::Fist => {
                let (a, b) = (back(1), back(2));
                Some(ThumbTarget {
                    point: scale(add(a.point, b.point), 0.5),
                    normal: normalize(add(a.normal, b.normal)),
                })
            }
        }
    }
}

/// The distal joint's flexion coupled to the middle one's (degrees): DIP ≈ ⅔ PIP.
fn coupled_dip(pip: f64) -> f64 {
    2.0 * pip / 3.0
}

/// Places the thumb of `pose` on the gesture's target: minimises the distance from the
/// thumb's pad (`CONTACT_GAP` off the surface) to the target point, plus how far the pad's
/// normal is from facing the target, over (spread, opposition, CMC, MCP, IP) within their
/// ranges, by Nelder–Mead from three starting thumbs.
fn place_thumb(gesture: HandGesture, shape: &HandShape, pose: &mut HandPose) {
    let sections = digit_sections(shape, pose);
    let Some(target) = gesture.thumb_target(&sections) else {
        return;
    };
    let goal = add(target.point, scale(target.normal, CONTACT_GAP));
    let length = shape.hand_length();
    let with = |x: &[f64; 5]| {
        let mut p = *pose;
        p.spread[0] = x[0];
        p.opposition = x[1];
        p.flexion[0] = [x[2], x[3], x[4]];
        p.clamped()
    };
    let cost = |x: &[f64; 5]| {
        let p = with(x);
        let thumb = digit_sections(shape, &p)[0];
        let reach = norm(sub(thumb[4].surface_point(-1.0), goal)) / length;
        // The pad's outward normal is −dorsal; facing the target means opposite normals.
        let facing = 1.0 - dot(scale(thumb[4].dorsal, -1.0), scale(target.normal, -1.0));
        let through_palm: f64 = thumb[1..]
            .iter()
            .map(|s| depth_in_palm(shape, s) / length)
            .map(|d| d * d)
            .sum();
        reach * reach + 0.002 * facing + 1e4 * through_palm
    };
    // Three starts, from a half-opposed to a fully opposed thumb; the best is kept.
    let best = [
        [10.0, 40.0, 15.0, 20.0, 20.0],
        [0.0, 70.0, 10.0, 40.0, 20.0],
        [-5.0, 85.0, 20.0, 50.0, 30.0],
    ]
    .map(|start| nelder_mead(&cost, start.map(f64::to_radians), 0.3, 400))
    .into_iter()
    .min_by(|a, b| cost(a).total_cmp(&cost(b)))
    .unwrap_or_default();
    *pose = with(&best);
}

/// How deep (mm) the thumb section `s` reaches into the palm from its palmar side, for a
/// straight wrist: 0 when it stays in front of the palm or beside it.
fn depth_in_palm(shape: &HandShape, s: &DigitSection) -> f64 {
    let (half_width, length) = (0.5 * shape.palm_width, shape.palm_length);
    let [x, y, z] = s.centre;
    if x.abs() > half_width || !(0.1 * length..length).contains(&y) {
        return 0.0;
    }
    let radius = s.dorsal_half.max(s.palmar_half);
    (z + radius + 0.5 * shape.palm_thickness).max(0.0)
}

/// Minimises `f` by the Nelder–Mead simplex method from `start` with initial steps `step`,
/// for `iterations` iterations (deterministic).
fn nelder_mead<const N: usize>(
    f: &impl Fn(&[f64; N]) -> f64,
    start: [f64; N],
    step: f64,
    iterations: usize,
) -> [f64; N] {
    let mut simplex: Vec<([f64; N], f64)> = (0..=N)
        .map(|i| {
            let mut x = start;
            if i > 0 {
                x[i - 1] += step;
            }
            (x, f(&x))
        })
        .collect();
    let blend = |a: &[f64; N], b: &[f64; N], t: f64| -> [f64; N] {
        std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
    };
    for _ in 0..iterations {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let centroid: [f64; N] =
            std::array::from_fn(|k| simplex[..N].iter().map(|(x, _)| x[k]).sum::<f64>() / N as f64);
        let (worst, worst_cost) = simplex[N];
        let reflected = blend(&centroid, &worst, -1.0);
        let reflected_cost = f(&reflected);
        if reflected_cost < simplex[0].1 {
            let expanded = blend(&centroid, &worst, -2.0);
            let expanded_cost = f(&expanded);
            simplex[N] = if expanded_cost < reflected_cost {
                (expanded, expanded_cost)
            } else {
                (reflected, reflected_cost)
            };
        } else if reflected_cost < simplex[N - 1].1 {
            simplex[N] = (reflected, reflected_cost);
        } else {
            let contracted = blend(&centroid, &worst, 0.5);
            let contracted_cost = f(&contracted);
            if contracted_cost < worst_cost {
                simplex[N] = (contracted, contracted_cost);
            } else {
                let best = simplex[0].0;
                for vertex in simplex.iter_mut().skip(1) {
                    vertex.0 = blend(&best, &vertex.0, 0.5);
                    vertex.1 = f(&vertex.0);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex[0].0
}

/// A random pose of `shape`: a gesture drawn uniformly, its fingers jittered (SD 6°, DIP kept
/// coupled) and, for the free gestures, moved part of the way from rest; the thumb placed on
/// the jittered fingers; the wrist flexed and deviated (SD 15° and 8° about 5° ulnar).
/// Deterministic from `seed`.
///
/// ```
/// use meshgnn_data::{HandShape, random_hand_pose};
/// let shape = HandShape::adult();
/// let (gesture, pose) = random_hand_pose(&shape, 3);
/// assert_eq!((gesture, pose), random_hand_pose(&shape, 3));
/// assert!(pose.in_range());
/// ```
pub fn random_hand_pose(shape: &HandShape, seed: u64) -> (HandGesture, HandPose) {
    let mut rng = StdRng::seed_from_u64(seed);
    let gesture = HandGesture::ALL[rng.random_range(0..HandGesture::ALL.len())];
    let normal = |sd_deg: f64, rng: &mut StdRng| {
        Normal::new(0.0, sd_deg.to_radians())
            .map(|d| d.sample(rng))
            .unwrap_or(0.0)
    };
    let mut pose = gesture.finger_pose();
    if gesture.thumb_free() {
        let t = rng.random_range(0.3..1.0);
        pose = pose.relaxed(t, t);
        pose.opposition += rng.random_range(0.0..OPPOSITION_DEG[1] / 2.0).to_radians();
        for (angle, [lo, hi]) in pose.flexion[0].iter_mut().zip(THUMB_FLEXION_DEG) {
            *angle += rng.random_range(lo / 2.0..hi / 2.0).to_radians();
        }
    }
    for f in 1..5 {
        pose.flexion[f][0] += normal(6.0, &mut rng);
        pose.flexion[f][1] += normal(6.0, &mut rng);
        pose.flexion[f][2] = coupled_dip(pose.flexion[f][1]) + normal(3.0, &mut rng);
        pose.spread[f] += normal(2.0, &mut rng);
    }
    pose = pose.clamped();
    place_thumb(gesture, shape, &mut pose);
    pose.wrist = [
        normal(15.0, &mut rng),
        5f64.to_radians() + normal(8.0, &mut rng),
    ];
    (gesture, pose.clamped())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_the_minimum_of_a_quadratic() {
        let x = nelder_mead(
            &|x: &[f64; 3]| {
                (x[0] - 1.0).powi(2) + 2.0 * (x[1] + 0.5).powi(2) + (x[2] - 0.25).powi(2)
            },
            [0.0; 3],
            0.5,
            300,
        );
        assert!(
            (x[0] - 1.0).abs() < 1e-5 && (x[1] + 0.5).abs() < 1e-5 && (x[2] - 0.25).abs() < 1e-5,
            "{x:?}"
        );
    }

    #[test]
    fn the_thumb_reaches_its_target_in_the_contact_gestures() {
        for shape in [HandShape::adult(), HandShape::mean_for_age(5.0)] {
            for gesture in [
                HandGesture::Pinch,
                HandGesture::Fist,
                HandGesture::Point,
                HandGesture::Opposition,
            ] {
                let pose = gesture.pose(&shape);
                let sections = digit_sections(&shape, &pose);
                let target = gesture.thumb_target(&sections).unwrap();
                let pad = sections[0][4].surface_point(-1.0);
                let miss = norm(sub(pad, target.point)) / shape.hand_length();
                assert!(
                    miss < 0.1,
                    "{gesture:?} age {}: thumb {miss:.3} of the hand length away",
                    shape.age
                );
            }
        }
    }
}
