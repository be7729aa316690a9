//! LiDAR-like outdoor scans for the point-cloud simplifier (thesis ch. 5): a ground plane with
//! poles, buildings and cars, sampled by spinning multi-beam sensors along scan lines (ray
//! casting: the first hit of each beam at each azimuth step), with Gaussian range noise.
//! Millions of points come from several sensor positions, as in a mobile mapping run.
//!
//! # Conventions
//! - Metres, z up, ground at z = 0. Normals point towards the sensor side of the surface.

use meshgnn_geometry::PointCloud;
use rand::Rng;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

use crate::error::{Result, invalid};
use crate::vec3::item_seed;
use crate::vec3::{V3, add, scale, to_f32};

/// Scanner and scene parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LidarConfig {
    /// Seed of the scene layout and the noise.
    pub seed: u64,
    /// Sensor positions along the street.
    pub sensors: usize,
    /// Beams (elevation angles from −25° to +3°, like a 64-beam spinning sensor).
    pub beams: usize,
    /// Azimuth steps per revolution.
    pub azimuth_steps: usize,
    /// Range noise standard deviation (metres).
    pub range_noise: f64,
    /// Maximum range (metres).
    pub max_range: f64,
}

impl Default for LidarConfig {
    /// 16 sensors × 64 beams × 2048 steps ≈ 2 M rays.
    fn default() -> Self {
        Self {
            seed: 0,
            sensors: 16,
            beams: 64,
            azimuth_steps: 2048,
            range_noise: 0.02,
            max_range: 80.0,
        }
    }
}

#[derive(Clone, Copy)]
enum Solid {
    Box { lo: V3, hi: V3 },
    Pole { x: f64, y: f64, r: f64, h: f64 },
}

/// First hit of the ray `o + t d` (t in (0, t_max)) with `s`: `(t, normal)`.
fn hit(s: &Solid, o: V3, d: V3, t_max: f64) -> Option<(f64, V3)> {
    match *s {
        Solid::Box { lo, hi } => {
            let (mut t0, mut t1, mut axis) = (1e-6, t_max, 0usize);
            for k in 0..3 {
                if d[k].abs() < 1e-12 {
                    if o[k] < lo[k] || o[k] > hi[k] {
                        return None;
                    }
                    continue;
                }
                let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                let (near, far) = (a.min(b), a.max(b));
                if near > t0 {
                    t0 = near;
                    axis = k;
                }
                t1 = t1.min(far);
                if t0 > t1 {
                    return None;
                }
            }
            let mut n = [0.0; 3];
            n[axis] = -d[axis].signum();
            Some((t0, n))
        }
        Solid::Pole { x, y, r, h } => {
            let (ox, oy) = (o[0] - x, o[1] - y);
            let a = d[0] * d[0] + d[1] * d[1];
            if a < 1e-12 {
                return None;
            }
            let b = ox * d[0] + oy * d[1];
            let c = ox * ox + oy * oy - r * r;
            let disc = b * b - a * c;
            if disc < 0.0 {
                return None;
            }
            let t = (-b - disc.sqrt()) / a;
            let z = o[2] + t * d[2];
            if t <= 1e-6 || t >= t_max || !(0.0..=h).contains(&z) {
                return None;
            }
            let (px, py) = (ox + t * d[0], oy + t * d[1]);
            Some((t, [px / r, py / r, 0.0]))
        }
    }
}

/// A LiDAR scan of a random street scene: points `#P×3` with normals.
///
/// ```
/// use meshgnn_data::{LidarConfig, lidar_scene};
/// let cfg = LidarConfig { sensors: 1, beams: 8, azimuth_steps: 64, ..Default::default() };
/// let cloud = lidar_scene(&cfg)?;
/// assert!(cloud.len() > 200);
/// assert_eq!(cloud.points(), lidar_scene(&cfg)?.points());
/// // Everything lies on or above the ground (noise aside).
/// assert!(cloud.points().iter().all(|p| p[2] > -0.2));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn lidar_scene(cfg: &LidarConfig) -> Result<PointCloud> {
    if cfg.sensors == 0 || cfg.beams == 0 || cfg.azimuth_steps == 0 {
        return Err(invalid(
            "sensors/beams/azimuth_steps",
            0,
            "must all be positive",
        ));
    }
    if !(cfg.range_noise >= 0.0 && cfg.max_range > 0.0) {
        return Err(invalid(
            "range_noise/max_range",
            cfg.max_range,
            "noise ≥ 0, range > 0",
        ));
    }
    let mut rng = StdRng::seed_from_u64(cfg.seed);
    let street = 20.0 * cfg.sensors as f64;
    let mut solids = Vec::new();
    for side in [-1.0, 1.0] {
        let mut x = -30.0;
        while x < street + 30.0 {
            let w = rng.random_range(8.0..20.0);
            let depth = rng.random_range(8.0..15.0);
            let y0 = side * rng.random_range(9.0..12.0);
            let (ya, yb) = if side > 0.0 {
                (y0, y0 + depth)
            } else {
                (y0 - depth, y0)
            };
            solids.push(Solid::Box {
                lo: [x, ya, 0.0],
                hi: [x + w, yb, rng.random_range(6.0..25.0)],
            });
            x += w + rng.random_range(1.0..6.0);
        }
        let mut x = -20.0;
        while x < street + 20.0 {
            solids.push(Solid::Pole {
                x,
                y: side * 6.5,
                r: rng.random_range(0.08..0.25),
                h: rng.random_range(4.0..9.0),
            });
            x += rng.random_range(10.0..25.0);
        }
    }
    for _ in 0..(cfg.sensors * 2) {
        let x = rng.random_range(-10.0..street + 10.0);
        let y = if rng.random_bool(0.5) {
            rng.random_range(2.5..4.5)
        } else {
            -rng.random_range(2.5..4.5)
        };
        solids.push(Solid::Box {
            lo: [x, y - 0.9, 0.0],
            hi: [x + 4.3, y + 0.9, rng.random_range(1.4..1.9)],
        });
    }
    let rays = cfg.sensors * cfg.beams * cfg.azimuth_steps;
    let per_sensor = cfg.beams * cfg.azimuth_steps;
    let noise = Normal::new(0.0, cfg.range_noise)
        .map_err(|e| invalid("range_noise", cfg.range_noise, &e.to_string()))?;
    let hits: Vec<Option<([f32; 3], [f32; 3])>> = (0..rays)
        .into_par_iter()
        .map(|ray| {
            let sensor = ray / per_sensor;
            let (beam, step) = (
                (ray % per_sensor) / cfg.azimuth_steps,
                ray % cfg.azimuth_steps,
            );
            let o = [20.0 * sensor as f64, 0.0, 1.8];
            let elev = (-25.0 + 28.0 * beam as f64 / (cfg.beams.max(2) - 1) as f64).to_radians();
            let az = std::f64::consts::TAU * step as f64 / cfg.azimuth_steps as f64;
            let d = [elev.cos() * az.cos(), elev.cos() * az.sin(), elev.sin()];
            let mut best: Option<(f64, V3)> = None;
            let mut t_max = cfg.max_range;
            if d[2] < 0.0 {
                let t = -o[2] / d[2];
                if t < t_max {
                    best = Some((t, [0.0, 0.0, 1.0]));
                    t_max = t;
                }
            }
            for s in &solids {
                if let Some((t, n)) = hit(s, o, d, t_max) {
                    best = Some((t, n));
                    t_max = t;
                }
            }
            best.map(|(t, n)| {
                let mut r = StdRng::seed_from_u64(item_seed(cfg.seed, ray as u64));
                let t = t + noise.sample(&mut r);
                (to_f32(add(o, scale(d, t))), to_f32(n))
            })
        })
        .collect();
    let (points, normals): (Vec<_>, Vec<_>) = hits.into_iter().flatten().unzip();
    Ok(PointCloud::new(points)?.with_normals(normals)?)
}
