//! Per-subject hand shape: overall size, child-to-adult proportions, palm and finger dimensions,
//! knuckle and fingertip detail, and a seed for small smooth surface noise.
//!
//! Thesis ch. 3.3-3.4: the Handy model is built from 1208 subjects of all ages and evaluated on
//! children's hands (Table 3.2), whose anatomy differs from adults' mainly in proportions (a
//! relatively larger, thicker palm and shorter fingers). The growth curve and ratios below are
//! rounded anthropometric values (hand length ≈ 90 mm at age 1, ≈ 190 mm from age 16; finger
//! share of hand length ≈ 0.42 at age 1, 0.47 in adults). Lengths are in millimetres.

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, invalid};

/// Fingers in template order: thumb, index, middle, ring, little.
pub const FINGER_NAMES: [&str; 5] = ["thumb", "index", "middle", "ring", "little"];

/// One subject's hand shape. All lengths in millimetres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandShape {
    /// Age in years, `[1, 81]`.
    pub age: f64,
    /// Palm length, wrist crease to the knuckle line.
    pub palm_length: f64,
    /// Palm width across the knuckles.
    pub palm_width: f64,
    /// Palm thickness (dorsal to palmar).
    pub palm_thickness: f64,
    /// Per finger (thumb first): phalanx lengths `[proximal, middle, distal]`; for the thumb
    /// `[metacarpal, proximal, distal]`.
    pub phalanges: [[f64; 3]; 5],
    /// Per finger: half-width at the base.
    pub half_width: [f64; 5],
    /// Per finger: width at the tip divided by width at the base, `(0, 1]`.
    pub taper: [f64; 5],
    /// Knuckle bump height on the dorsal side of the joints.
    pub knuckle: f64,
    /// Fingertip pad thickness on the palmar side.
    pub fingertip_pad: f64,
    /// Amplitude of the smooth surface noise.
    pub noise_amplitude: f64,
    /// Seed of the smooth surface noise field.
    pub noise_seed: u64,
}

/// How child-like a hand of `age` years is: 1 at age 1, 0 from age 16, linear between.
fn childness(age: f64) -> f64 {
    ((16.0 - age) / 15.0).clamp(0.0, 1.0)
}

impl HandShape {
    /// The mean adult hand (age 30, hand length 190 mm, no noise): the template's rest shape.
    ///
    /// ```
    /// let s = meshgnn_data::HandShape::adult();
    /// assert!((s.palm_length + s.phalanges[2].iter().sum::<f64>() - 190.0).abs() < 1e-9);
    /// ```
    pub fn adult() -> Self {
        Self::mean_for_age(30.0)
    }

    /// The mean shape of a hand of `age` years (no individual variation).
    ///
    /// ```
    /// use meshgnn_data::HandShape;
    /// let (child, adult) = (HandShape::mean_for_age(4.0), HandShape::adult());
    /// let finger_share = |s: &HandShape| {
    ///     let f: f64 = s.phalanges[2].iter().sum();
    ///     f / (f + s.palm_length)
    /// };
    /// assert!(finger_share(&child) < finger_share(&adult));
    /// ```
    pub fn mean_for_age(age: f64) -> Self {
        let c = childness(age);
        let hand_length = 190.0 - 100.0 * c;
        let finger_share = 0.47 - 0.05 * c;
        let middle = hand_length * finger_share;
        let palm_length = hand_length - middle;
        let palm_width = hand_length * (0.45 + 0.05 * c);
        let palm_thickness = hand_length * (0.145 + 0.03 * c);
        // Finger lengths relative to the middle finger (thumb: metacarpal + 2 phalanges).
        let relative = [1.12, 0.92, 1.0, 0.95, 0.76];
        let split = [
            [0.42, 0.33, 0.25],
            [0.46, 0.30, 0.24],
            [0.46, 0.31, 0.23],
            [0.46, 0.31, 0.23],
            [0.45, 0.30, 0.25],
        ];
        let mut phalanges = [[0.0; 3]; 5];
        for f in 0..5 {
            for j in 0..3 {
                phalanges[f][j] = middle * relative[f] * split[f][j];
            }
        }
        // Base half-widths: fingers share the knuckle line with three webs.
        let width_share = [0.125, 0.105, 0.108, 0.100, 0.088];
        let half_width = width_share.map(|s| s * palm_width);
        Self {
            age,
            palm_length,
            palm_width,
            palm_thickness,
            phalanges,
            half_width,
            taper: [0.82, 0.78, 0.78, 0.78, 0.76],
            knuckle: 1.5 * (1.0 - c),
            fingertip_pad: 1.0,
            noise_amplitude: 0.0,
            noise_seed: 0,
        }
    }

    /// A random subject of `age` years: the mean for that age with individual variation
    /// (overall size ±6 %, palm ratios ±4 %, finger lengths and widths ±4 %, taper, knuckle
    /// and pad detail, noise amplitude 0.1-0.4 mm), deterministic from `seed`.
    ///
    /// Fails when `age` is outside `[1, 81]`.
    ///
    /// ```
    /// use meshgnn_data::HandShape;
    /// let a = HandShape::random(25.0, 7)?;
    /// assert_eq!(a, HandShape::random(25.0, 7)?);
    /// assert_ne!(a, HandShape::random(25.0, 8)?);
    /// assert!(HandShape::random(0.5, 7).is_err());
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn random(age: f64, seed: u64) -> Result<Self> {
        if !(1.0..=81.0).contains(&age) {
            return Err(invalid("age", age, "must be in [1, 81] years"));
        }
        let mut rng = StdRng::seed_from_u64(seed);
        let mut s = Self::mean_for_age(age);
        let jitter = |sd: f64, rng: &mut StdRng| -> f64 {
            let n = Normal::new(1.0, sd).map(|d| d.sample(rng)).unwrap_or(1.0);
            n.clamp(1.0 - 2.5 * sd, 1.0 + 2.5 * sd)
        };
        let size = jitter(0.06, &mut rng);
        s.palm_length *= size * jitter(0.04, &mut rng);
        s.palm_width *= size * jitter(0.04, &mut rng);
        s.palm_thickness *= size * jitter(0.05, &mut rng);
        let finger_scale = jitter(0.04, &mut rng);
        let width_scale = jitter(0.04, &mut rng);
        for f in 0..5 {
            let length = size * finger_scale * jitter(0.03, &mut rng);
            for j in 0..3 {
                s.phalanges[f][j] *= length * jitter(0.03, &mut rng);
            }
            s.half_width[f] *= size * width_scale * jitter(0.03, &mut rng);
            s.taper[f] = (s.taper[f] * jitter(0.04, &mut rng)).clamp(0.6, 0.95);
        }
        s.knuckle *= rng.random_range(0.5..1.5);
        s.fingertip_pad *= rng.random_range(0.5..1.5);
        s.noise_amplitude = rng.random_range(0.1..0.4);
        s.noise_seed = rng.random();
        Ok(s)
    }

    /// Overall hand length: palm plus middle finger.
    pub fn hand_length(&self) -> f64 {
        self.palm_length + self.phalanges[2].iter().sum::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_have_relatively_larger_palms_and_shorter_fingers() {
        for age in [1.0, 4.0, 8.0, 11.0] {
            let child = HandShape::mean_for_age(age);
            let adult = HandShape::adult();
            assert!(child.hand_length() < adult.hand_length());
            assert!(
                child.palm_width / child.hand_length() > adult.palm_width / adult.hand_length()
            );
            assert!(
                child.palm_length / child.hand_length() > adult.palm_length / adult.hand_length()
            );
        }
        assert!((HandShape::mean_for_age(1.0).hand_length() - 90.0).abs() < 1e-9);
    }

    #[test]
    fn random_shapes_stay_near_the_mean() {
        for seed in 0..50 {
            let s = HandShape::random(40.0, seed).unwrap();
            let m = HandShape::mean_for_age(40.0);
            assert!((s.hand_length() / m.hand_length() - 1.0).abs() < 0.3);
            assert!(s.taper.iter().all(|t| (0.6..=0.95).contains(t)));
        }
    }
}
