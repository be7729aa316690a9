//! The procedural face template: the front and sides of a head as a regular quad grid on an
//! ellipsoid (open at the back, like registered 4DFAB face scans, thesis ch. 4.4.1), with
//! eye sockets, eyeballs, brows, nose, lips, a mouth opening, cheeks, chin and jaw produced by
//! smooth identity displacements. Every subject shares the grid topology.
//!
//! # Conventions
//! - Millimetres; the face looks towards +z, +y is up, the head centre is at the origin.
//! - Chart coordinates `(X, Y)` per vertex: `X = cos φ sin θ`, `Y = sin φ` for longitude θ
//!   and latitude φ; features are placed in these coordinates.
//! - Boundary: two loops — the outer rim of the grid and the mouth opening (a slit of removed
//!   quads between the lips).

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, invalid};
use crate::vec3::{add, normalize, scale, to_f32};

/// Longitude half-range of the grid (radians, ≈ 109°).
const THETA_MAX: f64 = 1.9;
/// Latitude range of the grid (radians).
const PHI_RANGE: [f64; 2] = [-1.0, 1.25];
/// Vertical chart coordinate of the mouth line.
pub(crate) const MOUTH_Y: f64 = -0.33;
/// Horizontal half-extent of the mouth opening in chart coordinates.
pub(crate) const MOUTH_HALF_WIDTH: f64 = 0.28;
/// Horizontal chart position of the eyes.
pub(crate) const EYE_X: f64 = 0.3;

/// Identity parameters of one subject (millimetres or multipliers of the mean).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceIdentity {
    /// Ellipsoid half-axes: width (x), height (y), depth (z).
    pub radii: [f64; 3],
    /// Nose protrusion.
    pub nose: f64,
    /// Nose length and width multipliers.
    pub nose_shape: [f64; 2],
    /// Eye socket depth.
    pub eye_depth: f64,
    /// Brow ridge height.
    pub brow: f64,
    /// Lip fullness.
    pub lips: f64,
    /// Mouth width multiplier.
    pub mouth_width: f64,
    /// Chin protrusion.
    pub chin: f64,
    /// Cheek fullness.
    pub cheeks: f64,
    /// Jaw width multiplier.
    pub jaw_width: f64,
    /// Smooth surface noise amplitude.
    pub noise_amplitude: f64,
    /// Seed of the surface noise.
    pub noise_seed: u64,
}

impl FaceIdentity {
    /// The mean face.
    pub fn mean() -> Self {
        Self {
            radii: [72.0, 100.0, 92.0],
            nose: 22.0,
            nose_shape: [1.0, 1.0],
            eye_depth: 9.0,
            brow: 4.0,
            lips: 5.0,
            mouth_width: 1.0,
            chin: 6.0,
            cheeks: 4.0,
            jaw_width: 1.0,
            noise_amplitude: 0.0,
            noise_seed: 0,
        }
    }

    /// A random identity around [`FaceIdentity::mean`] (±5-20 % per parameter), from `seed`.
    ///
    /// ```
    /// use meshgnn_data::FaceIdentity;
    /// assert_eq!(FaceIdentity::random(1), FaceIdentity::random(1));
    /// assert_ne!(FaceIdentity::random(1), FaceIdentity::random(2));
    /// ```
    pub fn random(seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut j = |sd: f64| {
            Normal::new(1.0, sd)
                .map(|d| d.sample(&mut rng))
                .unwrap_or(1.0)
                .clamp(1.0 - 2.5 * sd, 1.0 + 2.5 * sd)
        };
        let m = Self::mean();
        let size = j(0.05);
        Self {
            radii: [
                m.radii[0] * size * j(0.04),
                m.radii[1] * size * j(0.04),
                m.radii[2] * size * j(0.04),
            ],
            nose: m.nose * j(0.15),
            nose_shape: [j(0.1), j(0.12)],
            eye_depth: m.eye_depth * j(0.15),
            brow: m.brow * j(0.2),
            lips: m.lips * j(0.2),
            mouth_width: j(0.08),
            chin: m.chin * j(0.2),
            cheeks: m.cheeks * j(0.25),
            jaw_width: j(0.06),
            noise_amplitude: 0.3 * j(0.3),
            noise_seed: rng.random(),
        }
    }
}

/// `exp(−(d/σ)²)`.
#[inline]
pub(crate) fn gauss(d: f64, sigma: f64) -> f64 {
    (-(d / sigma) * (d / sigma)).exp()
}

/// Smooth step from 0 at `a` to 1 at `b` (either order).
#[inline]
pub(crate) fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The face grid template.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceTemplate {
    columns: usize,
    rows: usize,
    angles: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
    mouth_rows: [usize; 2],
}

impl Default for FaceTemplate {
    /// The 72 × 70 grid (5 040 vertices).
    fn default() -> Self {
        Self::build(72, 70)
    }
}

impl FaceTemplate {
    /// A `columns × rows` grid template, both in `24..=512`.
    ///
    /// ```
    /// use meshgnn_data::FaceTemplate;
    /// let t = FaceTemplate::new(72, 70)?;
    /// assert_eq!(t.vertex_count(), 5040);
    /// assert!(FaceTemplate::new(4, 70).is_err());
    /// # Ok::<(), meshgnn_data::Error>(())
    /// ```
    pub fn new(columns: usize, rows: usize) -> Result<Self> {
        for (name, n) in [("columns", columns), ("rows", rows)] {
            if !(24..=512).contains(&n) {
                return Err(invalid(name, n, "must be in 24..=512"));
            }
        }
        Ok(Self::build(columns, rows))
    }

    fn build(columns: usize, rows: usize) -> Self {
        let mut angles = Vec::with_capacity(columns * rows);
        for j in 0..rows {
            let phi = PHI_RANGE[0] + (PHI_RANGE[1] - PHI_RANGE[0]) * j as f64 / (rows - 1) as f64;
            for i in 0..columns {
                let theta = -THETA_MAX + 2.0 * THETA_MAX * i as f64 / (columns - 1) as f64;
                angles.push([theta, phi]);
            }
        }
        // The mouth gap lies between the two rows around MOUTH_Y.
        let lower = (0..rows - 1)
            .rev()
            .find(|&j| angles[j * columns][1].sin() <= MOUTH_Y)
            .unwrap_or(0);
        let mut triangles = Vec::with_capacity(2 * (columns - 1) * (rows - 1));
        let idx = |i: usize, j: usize| (j * columns + i) as u32;
        for j in 0..rows - 1 {
            for i in 0..columns - 1 {
                if j == lower {
                    let [t0, p0] = angles[idx(i, j) as usize];
                    let [t1, _] = angles[idx(i + 1, j) as usize];
                    let x0 = p0.cos() * t0.sin();
                    let x1 = p0.cos() * t1.sin();
                    if x0.abs() < MOUTH_HALF_WIDTH && x1.abs() < MOUTH_HALF_WIDTH {
                        continue;
                    }
                }
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Self {
            columns,
            rows,
            angles,
            triangles,
            mouth_rows: [lower, lower + 1],
        }
    }

    /// Number of vertices `#V`.
    pub fn vertex_count(&self) -> usize {
        self.angles.len()
    }

    /// The shared triangles `#F×3`.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Grid size `(columns, rows)`.
    pub fn grid(&self) -> (usize, usize) {
        (self.columns, self.rows)
    }

    /// Chart coordinates `(X, Y)` of every vertex, `#V×2`.
    pub fn chart(&self) -> Vec<[f64; 2]> {
        self.angles
            .iter()
            .map(|&[t, p]| [p.cos() * t.sin(), p.sin()])
            .collect()
    }

    /// Chart `Y` midway between the lower- and upper-lip rows (the mouth opening).
    pub fn mouth_line(&self) -> f64 {
        let y = |j: usize| {
            self.angles
                .get(j * self.columns)
                .map_or(MOUTH_Y, |a| a[1].sin())
        };
        0.5 * (y(self.mouth_rows[0]) + y(self.mouth_rows[1]))
    }

    /// The neutral face of `identity`, `#V×3` (millimetres).
    ///
    /// ```
    /// use meshgnn_data::{FaceIdentity, FaceTemplate};
    /// let t = FaceTemplate::default();
    /// let v = t.neutral(&FaceIdentity::mean());
    /// // The nose tip is the most forward point, near the middle.
    /// let tip = v.iter().max_by(|a, b| a[2].total_cmp(&b[2])).unwrap();
    /// assert!(tip[0].abs() < 5.0 && tip[2] > 100.0);
    /// ```
    pub fn neutral(&self, id: &FaceIdentity) -> Vec<[f32; 3]> {
        let mut rng = StdRng::seed_from_u64(id.noise_seed);
        let waves: Vec<([f64; 2], f64)> = (0..6)
            .map(|_| {
                let k = [rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0)];
                (k, rng.random_range(0.0..std::f64::consts::TAU))
            })
            .collect();
        let [a, b, c] = id.radii;
        let mw = MOUTH_HALF_WIDTH * id.mouth_width;
        self.angles
            .iter()
            .map(|&[theta, phi]| {
                let (x, y) = (phi.cos() * theta.sin(), phi.sin());
                let front = smoothstep(0.0, 0.35, theta.cos() * phi.cos());
                let jaw = 1.0 + (id.jaw_width - 1.0) * smoothstep(-0.2, -0.6, y);
                let p = [a * x * jaw, b * y, c * phi.cos() * theta.cos()];
                let n = normalize([p[0] / (a * a), p[1] / (b * b), p[2] / (c * c)]);
                let [nl, nw] = id.nose_shape;
                let mut d = 0.0;
                d += id.nose
                    * gauss(x, 0.1 * nw)
                    * (0.35 * gauss(y - 0.12, 0.14 * nl) + 0.75 * gauss(y + 0.03, 0.07));
                d += 0.25
                    * id.nose
                    * (gauss(x - 0.09 * nw, 0.05) + gauss(x + 0.09 * nw, 0.05))
                    * gauss(y + 0.06, 0.04);
                for s in [-1.0, 1.0] {
                    d -= id.eye_depth * gauss(x - s * EYE_X, 0.13) * gauss(y - 0.25, 0.09);
                    d += 0.55 * id.eye_depth * gauss(x - s * EYE_X, 0.07) * gauss(y - 0.25, 0.05);
                    d += id.brow * gauss(x - s * EYE_X, 0.17) * gauss(y - 0.41, 0.05);
                    d += id.cheeks * gauss(x - s * 0.45, 0.18) * gauss(y + 0.05, 0.18);
                }
                d += id.lips * gauss(x, 0.9 * mw) * gauss(y + 0.28, 0.035);
                d += id.lips * gauss(x, 0.8 * mw) * gauss(y + 0.39, 0.04);
                d -= 3.0 * gauss(x, mw) * gauss(y - MOUTH_Y, 0.03);
                d += id.chin * gauss(x, 0.18) * gauss(y + 0.62, 0.1);
                let noise: f64 = waves
                    .iter()
                    .map(|(k, ph)| (k[0] * x + k[1] * y + ph).sin())
                    .sum::<f64>()
                    / 6f64.sqrt();
                d = d * front + id.noise_amplitude * noise;
                to_f32(add(p, scale(n, d)))
            })
            .collect()
    }
}
