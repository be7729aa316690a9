//! Hand articulation: per-joint flexion, per-finger spread (abduction), thumb opposition,
//! palm cupping and wrist flexion/deviation, each within its anatomical range of motion.
//!
//! Thesis ch. 3.3: registered hand scans vary in pose as well as in shape, which makes the
//! shape space non-linear and is why spiral mesh autoencoders beat PCA there (ch. 3.4). The
//! ranges are active ranges of motion (fingers: MCP 90°, PIP 105°, DIP 80° of flexion; thumb
//! CMC, MCP, IP; wrist 50° flexion, 40° extension, 25° ulnar and 15° radial deviation), wide
//! enough for a closed fist; contact between digits is resolved when the mesh is generated
//! (see `HandSetConfig::sample`), not by narrowing the ranges.

/// Joint angles in radians. Fingers are ordered thumb, index, middle, ring, little.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HandPose {
    /// Flexion of the three joints of each finger (MCP, PIP, DIP; thumb: CMC, MCP, IP),
    /// positive towards the palm (the thumb: towards its pad, across the palm).
    pub flexion: [[f64; 3]; 5],
    /// Spread of each finger about the palm normal at its base, positive away from the
    /// middle finger (thumb: radial abduction, away from the index).
    pub spread: [f64; 5],
    /// Thumb opposition: palmar abduction of the thumb's metacarpal out of the palm plane,
    /// with the pronation that turns its pad towards the fingers.
    pub opposition: f64,
    /// Deepening of the palm's transverse arch, `[0, 1]` (a cupped palm in a grasp).
    pub cupping: f64,
    /// Wrist `[flexion, deviation]`: flexion positive towards the palm, deviation positive
    /// towards the little finger (ulnar).
    pub wrist: [f64; 2],
}

/// Range `[min, max]` in degrees of each finger joint's flexion (MCP, PIP, DIP).
pub const FINGER_FLEXION_DEG: [[f64; 2]; 3] = [[-20.0, 90.0], [0.0, 105.0], [-5.0, 80.0]];
/// Range in degrees of the thumb's flexion (CMC, MCP, IP).
pub const THUMB_FLEXION_DEG: [[f64; 2]; 3] = [[-10.0, 5.0], [-10.0, 60.0], [-10.0, 80.0]];
/// Range in degrees of the spread of each finger (thumb first).
pub const SPREAD_DEG: [[f64; 2]; 5] = [
    [-10.0, 45.0],
    [-5.0, 20.0],
    [-5.0, 5.0],
    [-5.0, 12.0],
    [-5.0, 25.0],
];
/// Range in degrees of thumb opposition.
pub const OPPOSITION_DEG: [f64; 2] = [0.0, 90.0];
/// Range in degrees of wrist flexion (negative: extension) and deviation (negative: radial).
pub const WRIST_DEG: [[f64; 2]; 2] = [[-40.0, 50.0], [-15.0, 25.0]];

impl HandPose {
    /// The flat rest pose (all angles zero).
    pub fn rest() -> Self {
        Self::default()
    }

    /// This pose moved part of the way from the rest pose: the thumb's angles (flexion,
    /// spread, opposition) scaled by `thumb`, the other fingers' and the cupping by
    /// `fingers`, both in `[0, 1]`; the wrist is kept. `relaxed(1, 1)` is the pose itself.
    ///
    /// ```
    /// use meshgnn_data::HandPose;
    /// let mut p = HandPose::rest();
    /// p.flexion[0][1] = 1.0;
    /// p.flexion[2][1] = 1.0;
    /// p.wrist[0] = 0.5;
    /// let r = p.relaxed(0.25, 0.5);
    /// assert_eq!((r.flexion[0][1], r.flexion[2][1], r.wrist[0]), (0.25, 0.5, 0.5));
    /// ```
    pub fn relaxed(&self, thumb: f64, fingers: f64) -> Self {
        let mut out = *self;
        for f in 0..5 {
            let t = if f == 0 { thumb } else { fingers };
            out.flexion[f] = self.flexion[f].map(|a| a * t);
            out.spread[f] = self.spread[f] * t;
        }
        out.opposition = self.opposition * thumb;
        out.cupping = self.cupping * fingers;
        out
    }

    /// This pose with every angle clamped into its range.
    pub fn clamped(&self) -> Self {
        let clamp = |a: f64, r: [f64; 2]| a.clamp(r[0].to_radians(), r[1].to_radians());
        let mut out = *self;
        for (f, spread_range) in SPREAD_DEG.into_iter().enumerate() {
            for (j, range) in flexion_range(f).into_iter().enumerate() {
                out.flexion[f][j] = clamp(self.flexion[f][j], range);
            }
            out.spread[f] = clamp(self.spread[f], spread_range);
        }
        out.opposition = clamp(self.opposition, OPPOSITION_DEG);
        out.cupping = self.cupping.clamp(0.0, 1.0);
        out.wrist = [0, 1].map(|k| clamp(self.wrist[k], WRIST_DEG[k]));
        out
    }

    /// True when every angle lies in its documented range (with a 1e-9 tolerance).
    ///
    /// ```
    /// use meshgnn_data::HandPose;
    /// assert!(HandPose::rest().in_range());
    /// let mut p = HandPose::rest();
    /// p.flexion[1][1] = 3.0;
    /// assert!(!p.in_range());
    /// assert!(p.clamped().in_range());
    /// ```
    pub fn in_range(&self) -> bool {
        let clamped = self.clamped();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9;
        (0..5).all(|f| {
            (0..3).all(|j| close(self.flexion[f][j], clamped.flexion[f][j]))
                && close(self.spread[f], clamped.spread[f])
        }) && close(self.opposition, clamped.opposition)
            && close(self.cupping, clamped.cupping)
            && (0..2).all(|k| close(self.wrist[k], clamped.wrist[k]))
    }
}

/// The flexion ranges of finger `f` (thumb first).
pub(crate) fn flexion_range(f: usize) -> [[f64; 2]; 3] {
    if f == 0 {
        THUMB_FLEXION_DEG
    } else {
        FINGER_FLEXION_DEG
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamping_brings_every_angle_into_its_range() {
        let mut p = HandPose::rest();
        p.flexion = [[9.0; 3]; 5];
        p.spread = [-9.0; 5];
        p.opposition = 9.0;
        p.cupping = 2.0;
        p.wrist = [-9.0, 9.0];
        assert!(!p.in_range());
        let c = p.clamped();
        assert!(c.in_range());
        assert_eq!(c.flexion[1][1], 105f64.to_radians());
        assert_eq!(c.wrist, [-40f64.to_radians(), 25f64.to_radians()]);
        assert_eq!(c.cupping, 1.0);
    }
}
