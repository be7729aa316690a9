//! The procedural face template: the front and sides of a head as a regular quad grid
//! (open at the back, like registered 4DFAB face scans, thesis ch. 4.4.1), with eye sockets,
//! eyeballs and almond-shaped lid openings, brows, nose, lips, a mouth opening, cheekbones,
//! cheeks, nasolabial folds, chin and jaw line produced by smooth identity displacements.
//! Every subject shares the grid topology.
//!
//! # Conventions
//! - Millimetres; the face looks towards +z, +y is up, the head centre is at the origin.
//! - Chart coordinates `(X, Y)` per vertex: `X = cos φ sin θ`, `Y = sin φ` for longitude θ
//!   and latitude φ; features are placed in these coordinates. `y = b·Y` exactly (`b` the
//!   head's half height), so a chart step in `Y` of 0.01 is `b/100` ≈ 1 mm.
//! - The grid is denser over the face than over the crown and the sides (rows 2.2×, columns
//!   2.6× as dense between the chin and the brows and out to the cheekbones: rows ≈ 2.3 mm
//!   and columns ≈ 2.7 mm apart there), so the eyes and lips span several rows.
//! - The base surface is head-like: an ellipsoid whose front is flattened (half its
//!   curvature at the midline), whose sides are squared off, whose upper half is a
//!   super-ellipse (broad forehead, flat crown) and whose lower face tapers towards the chin;
//!   features are displacements along its normal.
//! - Boundary: two loops — the outer rim of the grid and the mouth opening (a slit of removed
//!   quads between the lips).

use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, invalid};
use crate::vec3::{V3, add, cross, normalize, scale, sub, to_f32};

/// Longitude half-range of the grid (radians, ≈ 109°).
const THETA_MAX: f64 = 1.9;
/// Latitude range of the grid (radians).
const PHI_RANGE: [f64; 2] = [-1.0, 1.25];
/// Grid density over the face relative to the rest: rows between latitudes
/// [`FACE_ROWS`] and columns between longitudes ±[`FACE_COLUMNS`] are this many times
/// denser than the crown, the chin's underside and the sides.
const FACE_DENSITY: [f64; 2] = [2.2, 2.6];
/// Latitude band of the dense rows (radians; the chin to above the brows).
const FACE_ROWS: [f64; 2] = [-0.6, 0.55];
/// Longitude half-width of the dense columns (radians; out to the cheekbones).
const FACE_COLUMNS: f64 = 0.75;
/// Front flattening of the base surface: `z ∝ u (1 + k (1 − u²))` for `u = cos θ`, which
/// halves the curvature at the midline for `k = 0.25`.
const FRONT_FLATTENING: f64 = 0.25;
/// Side squaring: `x ∝ s (1 + k (1 − s²))` for `s = sin θ`.
const SIDE_SQUARING: f64 = 0.12;
/// Narrowing of the lower face towards the chin (fraction of the width at the chin).
const JAW_TAPER: f64 = 0.35;
/// Exponent of the super-ellipse profile of the upper head (2 would be the ellipsoid): a
/// broader forehead and a flatter crown.
const CRANIUM_EXPONENT: f64 = 2.6;
/// Fraction of the gap across the mouth slit closed in the neutral face (the lips meet).
const LIP_CLOSURE: f64 = 0.85;
/// Vertical chart coordinate of the mouth line.
pub(crate) const MOUTH_Y: f64 = -0.33;
/// Horizontal half-extent of the mouth opening in chart coordinates.
pub(crate) const MOUTH_HALF_WIDTH: f64 = 0.28;
/// Horizontal chart position of the eyes.
pub(crate) const EYE_X: f64 = 0.33;
/// Vertical chart position of the eyes (the centre of the lid opening).
pub(crate) const EYE_Y: f64 = 0.25;
/// Half width of the lid opening (chart units, ≈ 10.5 mm).
pub(crate) const EYE_HALF_WIDTH: f64 = 0.13;
/// Heights of the upper and lower lid margins above / below [`EYE_Y`] at the opening's
/// centre (chart units): an 11 mm high opening.
pub(crate) const LID_MARGINS: [f64; 2] = [0.06, 0.05];
/// Radius of the eyeball (mm), the sphere the upper lid slides over.
pub(crate) const EYEBALL_RADIUS: f64 = 12.0;

/// The lid margins `(upper, lower)` as chart offsets from [`EYE_Y`] at horizontal offset
/// `dx` from the eye centre: an almond, zero beyond [`EYE_HALF_WIDTH`] (the eye corners).
pub(crate) fn lid_margins(dx: f64) -> (f64, f64) {
    let u = dx / EYE_HALF_WIDTH;
    let h = (1.0 - u * u).max(0.0).sqrt();
    // The upper lid's highest point lies slightly towards the nose.
    let skew = 1.0 - 0.1 * u.clamp(-1.0, 1.0);
    (LID_MARGINS[0] * h * skew, -LID_MARGINS[1] * h)
}

/// Distance in the chart from `(x, y)` to the segment `a`–`b`.
pub(crate) fn segment_distance(x: f64, y: f64, a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((x - a[0]) * dx + (y - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    let (ex, ey) = (x - a[0] - t * dx, y - a[1] - t * dy);
    (ex * ex + ey * ey).sqrt()
}

/// The nasolabial fold of side `s = ±1`: from the nose wing to beside the mouth corner.
pub(crate) fn nasolabial_fold(s: f64) -> ([f64; 2], [f64; 2]) {
    ([s * 0.15, -0.1], [s * 0.34, -0.38])
}

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

/// The base surface of `id` at longitude `theta`, latitude `phi` (mm), before the feature
/// displacements: an ellipsoid with radii `id.radii`, its front flattened
/// ([`FRONT_FLATTENING`]), its sides squared ([`SIDE_SQUARING`]), its upper half a
/// super-ellipse ([`CRANIUM_EXPONENT`]), its lower face narrowed towards the chin
/// ([`JAW_TAPER`], `id.jaw_width`). `y = b sin φ` exactly.
fn base_surface(id: &FaceIdentity, theta: f64, phi: f64) -> V3 {
    let [a, b, c] = id.radii;
    let (st, ct) = theta.sin_cos();
    let sp = phi.sin();
    // Horizontal radius of the section at height sp: a super-circle above the middle
    // (broad forehead, flatter crown), the ellipse below it.
    let cp = if sp > 0.0 {
        (1.0 - sp.powf(CRANIUM_EXPONENT))
            .max(0.0)
            .powf(1.0 / CRANIUM_EXPONENT)
    } else {
        phi.cos()
    };
    let hx = st * (1.0 + SIDE_SQUARING * (1.0 - st * st));
    let hz = ct * (1.0 + FRONT_FLATTENING * (1.0 - ct * ct));
    let jaw = 1.0 + (id.jaw_width - 1.0) * smoothstep(-0.2, -0.6, sp)
        - JAW_TAPER * smoothstep(-0.25, -0.95, sp);
    [a * cp * hx * jaw, b * sp, c * cp * hz]
}

/// Density `1` outside `[lo, hi]`, `peak` inside, with smooth 0.1-radian shoulders.
fn band_density(t: f64, lo: f64, hi: f64, peak: f64) -> f64 {
    1.0 + (peak - 1.0) * smoothstep(lo - 0.1, lo + 0.05, t) * smoothstep(hi + 0.1, hi - 0.05, t)
}

/// `n ≥ 2` samples from `lo` to `hi` (both included) with spacing inversely proportional to
/// `density`: uniform in the cumulative density (trapezoid rule on 4 096 cells, inverted
/// linearly). Symmetric densities give symmetric samples up to rounding.
fn equidistributed(n: usize, lo: f64, hi: f64, density: impl Fn(f64) -> f64) -> Vec<f64> {
    const CELLS: usize = 4096;
    let h = (hi - lo) / CELLS as f64;
    let mut cdf = Vec::with_capacity(CELLS + 1);
    cdf.push(0.0);
    for k in 0..CELLS {
        let (a, b) = (lo + k as f64 * h, lo + (k + 1) as f64 * h);
        let last = cdf[k];
        cdf.push(last + 0.5 * h * (density(a) + density(b)));
    }
    let total = cdf[CELLS];
    let mut out = Vec::with_capacity(n);
    let mut k = 0;
    for j in 0..n {
        let target = total * j as f64 / (n - 1) as f64;
        while k + 1 < CELLS && cdf[k + 1] < target {
            k += 1;
        }
        let (c0, c1) = (cdf[k], cdf[k + 1]);
        let f = if c1 > c0 {
            ((target - c0) / (c1 - c0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(lo + (k as f64 + f) * h);
    }
    out[0] = lo;
    out[n - 1] = hi;
    out
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
        let row_density = |phi: f64| band_density(phi, FACE_ROWS[0], FACE_ROWS[1], FACE_DENSITY[0]);
        let column_density =
            |theta: f64| band_density(theta, -FACE_COLUMNS, FACE_COLUMNS, FACE_DENSITY[1]);
        let phis = equidistributed(rows, PHI_RANGE[0], PHI_RANGE[1], row_density);
        let thetas = equidistributed(columns, -THETA_MAX, THETA_MAX, column_density);
        for &phi in &phis {
            for &theta in &thetas {
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
        let mw = MOUTH_HALF_WIDTH * id.mouth_width;
        let mouth_line = self.mouth_line();
        let mouth_mm = id.radii[1] * mouth_line;
        self.angles
            .iter()
            .map(|&[theta, phi]| {
                let (x, y) = (phi.cos() * theta.sin(), phi.sin());
                let front = smoothstep(0.0, 0.35, theta.cos() * phi.cos());
                let p = base_surface(id, theta, phi);
                let e = 1e-5;
                let n = normalize(cross(
                    sub(
                        base_surface(id, theta + e, phi),
                        base_surface(id, theta - e, phi),
                    ),
                    sub(
                        base_surface(id, theta, phi + e),
                        base_surface(id, theta, phi - e),
                    ),
                ));
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
                    let (dx, dy) = (x - s * EYE_X, y - EYE_Y);
                    // Socket, eyeball, and the lids around an almond-shaped opening.
                    d -= 0.85 * id.eye_depth * gauss(dx, 0.14) * gauss(dy - 0.01, 0.1);
                    d += 0.6 * id.eye_depth * gauss(dx, 0.09) * gauss(dy, 0.065);
                    d += 2.0 * gauss(dx + s * 0.01, 0.045) * gauss(dy + 0.005, 0.035);
                    let (up, lo) = lid_margins(s * dx);
                    let inside = smoothstep(EYE_HALF_WIDTH, 0.75 * EYE_HALF_WIDTH, dx.abs());
                    d += 2.5 * inside * gauss(dy - up - 0.01, 0.02);
                    d += 1.2 * inside * gauss(dy - lo + 0.008, 0.018);
                    d -= 1.5 * gauss(dx, 0.1) * gauss(dy - LID_MARGINS[0] - 0.05, 0.02);
                    d += id.brow * gauss(dx, 0.17) * gauss(y - 0.41, 0.05);
                    // Cheeks, cheekbones, the hollow below them and the temples.
                    d += id.cheeks * gauss(x - s * 0.45, 0.18) * gauss(y + 0.05, 0.18);
                    d += 0.8 * id.cheeks * gauss(x - s * 0.52, 0.13) * gauss(y - 0.08, 0.07);
                    d -= 0.5 * id.cheeks * gauss(x - s * 0.56, 0.12) * gauss(y + 0.25, 0.1);
                    d -= 2.0 * gauss(x - s * 0.72, 0.1) * gauss(y - 0.35, 0.12);
                    let (fa, fb) = nasolabial_fold(s);
                    d -= 1.2 * gauss(segment_distance(x, y, fa, fb), 0.02);
                }
                d += id.lips * gauss(x, 0.9 * mw) * gauss(y + 0.28, 0.035);
                d += id.lips * gauss(x, 0.8 * mw) * gauss(y + 0.39, 0.04);
                d -= 3.0 * gauss(x, mw) * gauss(y - MOUTH_Y, 0.03);
                d += id.chin * gauss(x, 0.18) * gauss(y + 0.62, 0.1);
                d -= 1.5 * gauss(x, 0.15) * gauss(y + 0.49, 0.025);
                let noise: f64 = waves
                    .iter()
                    .map(|(k, ph)| (k[0] * x + k[1] * y + ph).sin())
                    .sum::<f64>()
                    / 6f64.sqrt();
                // The jaw line: below the mandible's lower border the surface turns in.
                let jaw_line = -0.8 + 0.33 * theta.sin().powi(2);
                let jaw = 3.0
                    * smoothstep(jaw_line + 0.02, jaw_line - 0.18, y)
                    * smoothstep(0.0, 0.4, theta.cos());
                d = d * front - jaw + id.noise_amplitude * noise;
                // The lips close over the mouth slit: the rows beside it are drawn towards the
                // mouth line, leaving a gap of a quarter of a row.
                let mut q = add(p, scale(n, d));
                let close = LIP_CLOSURE
                    * gauss(y - mouth_line, 0.035)
                    * smoothstep(MOUTH_HALF_WIDTH + 0.04, MOUTH_HALF_WIDTH - 0.02, x.abs());
                q[1] = mouth_mm + (q[1] - mouth_mm) * (1.0 - close);
                to_f32(q)
            })
            .collect()
    }
}
