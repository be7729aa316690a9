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
use crate::hand_pose::HandPose;
use crate::hand_shape::HandShape;
use crate::hand_template::{DEFAULT_HAND_SUBDIVISIONS, HandTemplate};
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
    /// Pose parameters.
    pub pose: HandPose,
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

    /// Subject `index` of the set: the same whatever the count or thread count.
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
        let shape = HandShape::random(age, rng.random())?;
        let pose_seed: u64 = rng.random();
        let pose = if self.articulated {
            HandPose::random(pose_seed)
        } else {
            HandPose::rest()
        };
        let split = match (held_out, child) {
            (true, true) => "children",
            (true, false) => "test",
            (false, _) => "train",
        };
        Ok(HandSample {
            name: format!("hand_{index:05}"),
            vertices: template.generate_vertices(&shape, &pose)?,
            shape,
            pose,
            split,
        })
    }
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
