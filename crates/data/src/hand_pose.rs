//! Hand articulation: per-joint flexion and per-finger spread (abduction), within plausible
//! ranges, applied by the template as rotations of the phalanges about their joint axes.
//!
//! Thesis ch. 3.3: registered hand scans vary in pose as well as in shape, which makes the
//! shape space non-linear and is why spiral mesh autoencoders beat PCA there (ch. 3.4). The
//! ranges are those of relaxed, non-contact poses (no finger touches another finger or the
//! palm), so generated meshes are free of self-intersections.

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;

/// Joint angles in radians. Fingers are ordered thumb, index, middle, ring, little.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HandPose {
    /// Flexion of the three joints of each finger (MCP, PIP, DIP; thumb: CMC, MCP, IP),
    /// positive towards the palm.
    pub flexion: [[f64; 3]; 5],
    /// Spread of each finger about the palm normal at its base, positive away from the
    /// middle finger (thumb: away from the index).
    pub spread: [f64; 5],
    /// Thumb opposition: rotation of the thumb towards the palm side at its base.
    pub opposition: f64,
}

/// Range `[min, max]` in degrees of each finger joint's flexion (MCP, PIP, DIP).
pub const FINGER_FLEXION_DEG: [[f64; 2]; 3] = [[-10.0, 50.0], [0.0, 65.0], [0.0, 45.0]];
/// Range in degrees of the thumb's flexion (CMC, MCP, IP).
pub const THUMB_FLEXION_DEG: [[f64; 2]; 3] = [[-10.0, 15.0], [0.0, 25.0], [0.0, 30.0]];
/// Range in degrees of the spread of each finger (thumb first).
pub const SPREAD_DEG: [[f64; 2]; 5] = [
    [-10.0, 25.0],
    [-2.0, 12.0],
    [-3.0, 3.0],
    [-2.0, 8.0],
    [-2.0, 15.0],
];
/// Range in degrees of thumb opposition.
pub const OPPOSITION_DEG: [f64; 2] = [0.0, 20.0];

impl HandPose {
    /// The flat rest pose (all angles zero).
    pub fn rest() -> Self {
        Self::default()
    }

    /// A random pose: a shared "grasp" level in `[0, 1]` moves all joints together (as real
    /// hands do), plus independent per-joint variation; every angle stays in its range.
    /// Deterministic from `seed`.
    ///
    /// ```
    /// use meshgnn_data::HandPose;
    /// let p = HandPose::random(3);
    /// assert_eq!(p, HandPose::random(3));
    /// assert!(p.flexion.iter().flatten().all(|a| a.abs() < 1.2));
    /// ```
    pub fn random(seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let grasp: f64 = rng.random_range(0.0..1.0);
        let spread_level: f64 = rng.random_range(0.0..1.0);
        let mut pose = Self::rest();
        let angle = |range: [f64; 2], level: f64, rng: &mut StdRng| {
            let t = (0.6 * level + 0.4 * rng.random_range(0.0..1.0)).clamp(0.0, 1.0);
            (range[0] + t * (range[1] - range[0])).to_radians()
        };
        for (f, spread_range) in SPREAD_DEG.iter().enumerate() {
            let ranges = if f == 0 {
                THUMB_FLEXION_DEG
            } else {
                FINGER_FLEXION_DEG
            };
            for (j, range) in ranges.iter().enumerate() {
                pose.flexion[f][j] = angle(*range, grasp, &mut rng);
            }
            pose.spread[f] = angle(*spread_range, spread_level, &mut rng);
        }
        pose.opposition = angle(OPPOSITION_DEG, grasp, &mut rng);
        pose
    }

    /// True when every angle lies in its documented range (with a 1e-9 tolerance).
    ///
    /// ```
    /// use meshgnn_data::HandPose;
    /// assert!(HandPose::rest().in_range());
    /// let mut p = HandPose::rest();
    /// p.flexion[1][1] = 3.0;
    /// assert!(!p.in_range());
    /// ```
    pub fn in_range(&self) -> bool {
        let inside =
            |a: f64, r: [f64; 2]| a >= r[0].to_radians() - 1e-9 && a <= r[1].to_radians() + 1e-9;
        (0..5).all(|f| {
            let ranges = if f == 0 {
                THUMB_FLEXION_DEG
            } else {
                FINGER_FLEXION_DEG
            };
            (0..3).all(|j| inside(self.flexion[f][j], ranges[j]))
                && inside(self.spread[f], SPREAD_DEG[f])
        }) && inside(self.opposition, OPPOSITION_DEG)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_poses_are_in_range_and_vary() {
        let poses: Vec<HandPose> = (0..200).map(HandPose::random).collect();
        assert!(poses.iter().all(HandPose::in_range));
        let max_pip = poses.iter().map(|p| p.flexion[2][1]).fold(0.0f64, f64::max);
        assert!(max_pip > 40f64.to_radians());
        assert_ne!(poses[0], poses[1]);
    }
}
