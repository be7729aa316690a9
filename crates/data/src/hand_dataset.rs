//! The synthetic hand dataset: `count` subjects, each a random shape (age 1-81) in a random
//! pose on one template, with subject-disjoint splits: `train`, held-out adults `test` and
//! held-out children `children`. As in the thesis (ch. 3.4.1-3.4.2, Table 3.2: a model built
//! from 1 208 subjects of every age, over 360 of them younger than 12, reconstructs 20
//! children's hands "not present in the training set"), the training set holds children
//! too, and the `children` split holds children it never saw.

use std::collections::BTreeMap;

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::error::{Result, invalid};
use crate::hand_gesture::{HandGesture, random_hand_pose};
use crate::hand_pose::HandPose;
use crate::hand_shape::HandShape;
use crate::hand_template::{DEFAULT_HAND_SUBDIVISIONS, HandTemplate};
use crate::self_intersections::self_intersections;
use crate::vec3::item_seed;

/// Age below which a subject is a child (held out into the `children` split, or trained on).
pub const CHILD_AGE: f64 = 12.0;

/// How to generate a hand set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandSetConfig {
    /// Number of subjects (one mesh each).
    pub count: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Catmull–Clark levels of the template (see [`HandTemplate::new`]).
    pub subdivisions: u32,
    /// Random poses when true; the flat rest pose when false (a pose-free variant).
    pub articulated: bool,
    /// Fraction of subjects younger than [`CHILD_AGE`], `[0, 1]` (the thesis' set: 0.3).
    pub children_fraction: f64,
    /// Fraction of subjects held out, `[0, 1]`: adults into `test`, children into `children`.
    pub test_fraction: f64,
}

impl Default for HandSetConfig {
    fn default() -> Self {
        Self {
            count: 1200,
            seed: 0,
            subdivisions: DEFAULT_HAND_SUBDIVISIONS,
            articulated: true,
            children_fraction: 0.3,
            test_fraction: 0.1,
        }
    }
}

/// One generated subject: its parameters, split and vertices `#V×3`.
#[derive(Debug, Clone, PartialEq)]
pub struct HandSample {
    /// File stem, `hand_00042`.
    pub name: String,
    /// Shape parameters (includes the age).
    pub shape: HandShape,
    /// The gesture the pose was drawn around (`Flat` for the pose-free variant).
    pub gesture: HandGesture,
    /// The pose drawn around the gesture.
    pub drawn_pose: HandPose,
    /// The pose of the mesh: the drawn one after contact resolution (see
    /// [`HandSetConfig::sample`]).
    pub pose: HandPose,
    /// The fractions `[thumb, fingers, wrist]` of the drawn pose kept by contact resolution
    /// (1: none needed; see [`relax_until_free`]).
    pub kept: [f64; 3],
    /// `train`, `test` or `children`.
    pub split: &'static str,
    /// Vertex positions `#V×3` on the template's triangles.
    pub vertices: Vec<[f32; 3]>,
}

impl HandSetConfig {
    /// Checks the ranges of the fields.
    pub fn validate(&self) -> Result<()> {
        if self.count == 0 {
            return Err(invalid("count", self.count, "must be at least 1"));
        }
        for (name, v) in [
            ("children_fraction", self.children_fraction),
            ("test_fraction", self.test_fraction),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(invalid(name, v, "must be in [0, 1]"));
            }
        }
        Ok(())
    }

    /// Subject `index` of the set: the same whatever the count or thread count. Where the
    /// drawn pose makes the surface pass through itself (the thumb into a finger, fingertips
    /// into the palm), the thumb and then, if that is not enough, all digits are relaxed
    /// towards rest in steps of 4 % until it does not: closed hands end in contact, never in
    /// interpenetration ([`relax_until_free`]). A subject whose hand intersects itself even at
    /// rest with a straight wrist (1 of the 1 200 of the default set, a one-year-old) is drawn
    /// again, up to [`SHAPE_DRAWS`] times.
    ///
    /// ```
    /// use meshgnn_data::{HandSetConfig, HandTemplate};
    /// let cfg = HandSetConfig { subdivisions: 1, ..Default::default() };
    /// let t = HandTemplate::new(1)?;
    /// let a = cfg.sample(&t, 5)?;
    /// assert_eq!(a, cfg.sample(&t, 5)?);
    /// assert_eq!(a.vertices.len(), t.vertex_count());
    /// assert_eq!(a.name, "hand_00005");
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn sample(&self, template: &HandTemplate, index: usize) -> Result<HandSample> {
        self.validate()?;
        let mut rng = StdRng::seed_from_u64(item_seed(self.seed, index as u64));
        let child = rng.random_range(0.0..1.0) < self.children_fraction;
        let age = if child {
            rng.random_range(1.0..CHILD_AGE)
        } else {
            rng.random_range(CHILD_AGE..81.0)
        };
        let held_out = rng.random_range(0.0..1.0) < self.test_fraction;
        let split = match (held_out, child) {
            (true, true) => "children",
            (true, false) => "test",
            (false, _) => "train",
        };
        for _ in 0..SHAPE_DRAWS {
            let shape = HandShape::random(age, rng.random())?;
            let pose_seed: u64 = rng.random();
            let (gesture, drawn) = if self.articulated {
                random_hand_pose(&shape, pose_seed)
            } else {
                (HandGesture::Flat, HandPose::rest())
            };
            if let Some(FreeHand { kept, vertices }) = relax_until_free(template, &shape, &drawn)? {
                return Ok(HandSample {
                    name: format!("hand_{index:05}"),
                    vertices,
                    shape,
                    gesture,
                    drawn_pose: drawn,
                    pose: relaxed_pose(&drawn, kept),
                    kept,
                    split,
                });
            }
        }
        Err(invalid(
            "hand",
            index,
            "every shape drawn intersects itself even at rest",
        ))
    }
}

/// How many subject shapes [`HandSetConfig::sample`] draws at most for one hand.
pub const SHAPE_DRAWS: usize = 8;

/// `pose` with the fractions `[thumb, fingers, wrist]` of its angles kept.
fn relaxed_pose(pose: &HandPose, kept: [f64; 3]) -> HandPose {
    HandPose {
        wrist: pose.wrist.map(|a| a * kept[2]),
        ..pose.relaxed(kept[0], kept[1])
    }
}

/// A hand mesh free of self-intersections and how much of the drawn pose it kept.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeHand {
    /// The fractions `[thumb, fingers, wrist]` of the pose's angles kept.
    pub kept: [f64; 3],
    /// The vertices `#V×3` on the template's triangles.
    pub vertices: Vec<[f32; 3]>,
}

/// The least relaxation of `pose` whose mesh does not intersect itself, as the fractions
/// `[thumb, fingers, wrist]` of its angles kept, with its vertices: first the thumb alone (1,
/// 0.96, 0.92, …, 0 of its angles), then all digits together, then, the digits at rest, the
/// wrist. `None` when even the rest pose with a straight wrist intersects itself (a shape
/// to draw again).
///
/// ```
/// use meshgnn_data::{HandGesture, HandShape, HandTemplate, relax_until_free};
/// let (t, shape) = (HandTemplate::new(1)?, HandShape::adult());
/// let free = relax_until_free(&t, &shape, &HandGesture::Flat.pose(&shape))?
///     .expect("the flat adult hand is free");
/// assert_eq!((free.kept, free.vertices.len()), ([1.0; 3], t.vertex_count()));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn relax_until_free(
    template: &HandTemplate,
    shape: &HandShape,
    pose: &HandPose,
) -> Result<Option<FreeHand>> {
    const STEPS: usize = 25;
    let fractions = (0..=STEPS).map(|step| 1.0 - step as f64 / STEPS as f64);
    let thumb_first = fractions.clone().map(|t| [t, 1.0, 1.0]);
    let all_digits = fractions.clone().skip(1).map(|t| [t, t, 1.0]);
    let wrist = fractions.skip(1).map(|t| [0.0, 0.0, t]);
    for kept in thumb_first.chain(all_digits).chain(wrist) {
        let mesh = template.generate(shape, &relaxed_pose(pose, kept))?;
        if self_intersections(&mesh) == 0 {
            return Ok(Some(FreeHand {
                kept,
                vertices: mesh.vertices().to_vec(),
            }));
        }
    }
    Ok(None)
}

/// The split lists (`train`, `test`, `children`) of `samples`, as file names with `extension`.
///
/// ```
/// use meshgnn_data::{HandSetConfig, HandTemplate, hand_splits};
/// let cfg = HandSetConfig { subdivisions: 1, count: 4, ..Default::default() };
/// let t = HandTemplate::new(1)?;
/// let samples: Vec<_> = (0..4).map(|i| cfg.sample(&t, i)).collect::<Result<_, _>>()?;
/// let splits = hand_splits(&samples, "ply");
/// assert_eq!(splits.values().map(Vec::len).sum::<usize>(), 4);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn hand_splits(samples: &[HandSample], extension: &str) -> BTreeMap<String, Vec<String>> {
    let mut splits: BTreeMap<String, Vec<String>> = ["train", "test", "children"]
        .iter()
        .map(|s| ((*s).to_string(), Vec::new()))
        .collect();
    for s in samples {
        splits
            .entry(s.split.to_string())
            .or_default()
            .push(format!("{}.{extension}", s.name));
    }
    splits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hand_template::digit_sections;
    use crate::vec3::{norm, sub};

    /// The hand closes: after contact resolution the fist's fingertips lie in front of the
    /// palm below the knuckle line, and the pinching thumb meets the index.
    #[test]
    fn fists_close_and_pinches_meet_after_contact_resolution() {
        let template = HandTemplate::new(2).unwrap();
        for age in [30.0, 6.0] {
            let shape = HandShape::mean_for_age(age);
            let length = shape.hand_length();
            for gesture in [HandGesture::Fist, HandGesture::Pinch] {
                let drawn = gesture.pose(&shape);
                let FreeHand { kept, vertices } = relax_until_free(&template, &shape, &drawn)
                    .unwrap()
                    .unwrap();
                let mesh = meshgnn_geometry::TriMesh::new(vertices, template.triangles().to_vec())
                    .unwrap();
                assert_eq!(self_intersections(&mesh), 0);
                eprintln!("{gesture:?} age {age}: kept {kept:?}");
                let sections = digit_sections(&shape, &relaxed_pose(&drawn, kept));
                match gesture {
                    HandGesture::Fist => {
                        for (finger, digit) in sections.iter().enumerate().skip(1) {
                            let tip = digit[5].centre;
                            assert!(tip[1] < shape.palm_length, "{finger} {tip:?}");
                            assert!(tip[2] < -0.5 * shape.palm_thickness, "{finger} {tip:?}");
                            assert!(tip[2] > -0.5 * shape.palm_thickness - 0.25 * length);
                        }
                    }
                    _ if age >= CHILD_AGE => {
                        let gap = norm(sub(
                            sections[0][4].surface_point(-1.0),
                            sections[1][4].surface_point(-1.0),
                        ));
                        assert!(
                            gap < 0.1 * length,
                            "age {age}: thumb {gap:.1} mm from the index"
                        );
                    }
                    _ => {}
                }
            }
        }
    }
}
