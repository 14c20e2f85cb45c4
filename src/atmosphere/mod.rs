//! Planet and cloud-shell geometry: where a view ray enters and leaves the cloud layer.
//!
//! The planet is a sphere of radius R whose center is at `-up * R`, so the world origin is on
//! the ground. The cloud layer is the shell between radii R + bottom and R + top. This module is
//! the CPU mirror of `shaders/atmosphere.wgsl`; both use the same formulation, which keeps
//! f32 precision at planetary radii: terms like |o - C|² - r² are expanded so that R² cancels
//! analytically instead of numerically, and quadratic roots use the stable form q = -b ∓ √Δ,
//! t₁ = q, t₂ = c / q.

use glam::Vec3;

/// The geometry the march needs, in meters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shell {
    /// Planet radius R.
    pub planet_radius: f32,
    /// Unit world up.
    pub up: Vec3,
    /// Altitude of the bottom of the layer.
    pub bottom: f32,
    /// Altitude of the top of the layer.
    pub top: f32,
}

/// Up to two parameter intervals [t0, t1] along a ray that lie inside the layer. A ray that
/// dips below the layer without hitting the ground crosses it twice.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segments {
    /// The intervals, nearest first; `None` when absent.
    pub spans: [Option<(f32, f32)>; 2],
}

impl Segments {
    /// Total length inside the layer.
    pub fn length(&self) -> f32 {
        self.spans.iter().flatten().map(|(a, b)| b - a).sum()
    }

    /// Whether the ray misses the layer entirely.
    pub fn is_empty(&self) -> bool {
        self.spans.iter().all(Option::is_none)
    }
}

/// Both roots (near, far) of a ray with the sphere at altitude `h` (radius R + h), or `None`
/// when the ray's line misses it. Roots can be negative (behind the origin).
pub fn sphere_roots(origin: Vec3, dir: Vec3, up: Vec3, radius: f32, h: f32) -> Option<(f32, f32)> {
    // oc = o + up R;  b = oc·d;  c = |oc|² - (R + h)² = |o|² + 2R (o·up) - 2R h - h².
    let b = origin.dot(dir) + radius * up.dot(dir);
    let c = origin.length_squared() + 2.0 * radius * origin.dot(up) - 2.0 * radius * h - h * h;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let q = -b - b.signum() * disc.sqrt();
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let (t1, t2) = (q, c / q);
    Some((t1.min(t2), t1.max(t2)))
}

/// Altitude of a world point above the planet surface, without cancelling R:
/// |p - C| - R = (|p|² + 2R p·up) / (|p - C| + R).
pub fn altitude(p: Vec3, up: Vec3, radius: f32) -> f32 {
    let num = p.length_squared() + 2.0 * radius * p.dot(up);
    let dist = (p + up * radius).length();
    num / (dist + radius)
}

impl Shell {
    /// The intervals of the ray `origin + t dir` (dir unit length) inside the layer, for t in
    /// [0, max_t]. Rays stop at the ground when the origin is above it; a camera below the
    /// ground (altitude < 0) sees through it.
    pub fn segments(&self, origin: Vec3, dir: Vec3, max_t: f32) -> Segments {
        let (r, up) = (self.planet_radius, self.up);
        let h = altitude(origin, up, r);
        let inner = sphere_roots(origin, dir, up, r, self.bottom);
        let outer = sphere_roots(origin, dir, up, r, self.top);

        let mut end = max_t;
        if h >= 0.0 {
            if let Some((g0, _)) = sphere_roots(origin, dir, up, r, 0.0) {
                if g0 > 0.0 {
                    end = end.min(g0);
                }
            }
        }

        // Where the ray would cross the layer, ignoring the ground and max_t.
        let raw: [Option<(f32, f32)>; 2] = if h < self.bottom {
            // Below: from leaving the inner sphere to leaving the outer one.
            match (inner, outer) {
                (Some((_, i1)), Some((_, o1))) => [Some((i1, o1)), None],
                _ => [None, None],
            }
        } else {
            let (start, o1) = match outer {
                Some((o0, o1)) if o1 > 0.0 => (if h > self.top { o0.max(0.0) } else { 0.0 }, o1),
                _ => return Segments::default(),
            };
            match inner {
                // The ray dips into the inner sphere ahead: the layer is crossed twice.
                Some((i0, i1)) if i0 > start => [Some((start, i0)), Some((i1, o1))],
                _ => [Some((start, o1)), None],
            }
        };

        let mut out = Segments::default();
        let mut n = 0;
        for (a, b) in raw.into_iter().flatten() {
            let (a, b) = (a.max(0.0), b.min(end));
            if b > a {
                out.spans[n] = Some((a, b));
                n += 1;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f32 = 6_360_000.0;

    fn shell() -> Shell {
        Shell {
            planet_radius: R,
            up: Vec3::Y,
            bottom: 1_500.0,
            top: 4_000.0,
        }
    }

    fn at(alt: f32) -> Vec3 {
        Vec3::new(0.0, alt, 0.0)
    }

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    fn span(s: &Segments, i: usize) -> (f32, f32) {
        s.spans[i].unwrap_or_else(|| panic!("no span {i} in {s:?}"))
    }

    #[test]
    fn altitude_is_exact_near_and_far() {
        assert!(close(altitude(at(1234.5), Vec3::Y, R), 1234.5, 1e-3));
        // 100 km away horizontally the ground has fallen by d² / 2R ≈ 786 m.
        let p = Vec3::new(100_000.0, 0.0, 0.0);
        let exact = ((R as f64).hypot(100_000.0) - R as f64) as f32;
        assert!(close(altitude(p, Vec3::Y, R), exact, 0.05));
    }

    #[test]
    fn from_the_ground_looking_up() {
        let s = shell().segments(at(0.0), Vec3::Y, 1e6);
        let (a, b) = span(&s, 0);
        assert!(close(a, 1_500.0, 0.05) && close(b, 4_000.0, 0.05), "{s:?}");
        assert!(s.spans[1].is_none());
    }

    #[test]
    fn from_the_ground_looking_down_sees_nothing() {
        assert!(shell().segments(at(2.0), -Vec3::Y, 1e6).is_empty());
        let slightly_down = Vec3::new(1.0, -0.01, 0.0).normalize();
        assert!(shell().segments(at(2.0), slightly_down, 1e6).is_empty());
    }

    #[test]
    fn grazing_the_horizon_from_the_ground() {
        // A horizontal ray from the ground meets the sphere of radius R + h at √((R+h)² - R²).
        let s = shell().segments(at(0.0), Vec3::X, 1e7);
        let d = |h: f64| (((R as f64) + h).powi(2) - (R as f64).powi(2)).sqrt() as f32;
        let (a, b) = span(&s, 0);
        assert!(close(a, d(1_500.0), 2.0), "{a} vs {}", d(1_500.0));
        assert!(close(b, d(4_000.0), 2.0), "{b} vs {}", d(4_000.0));
    }

    #[test]
    fn inside_the_layer() {
        let sh = shell();
        let up = sh.segments(at(2_500.0), Vec3::Y, 1e6);
        let (a, b) = span(&up, 0);
        assert!(close(a, 0.0, 1e-3) && close(b, 1_500.0, 0.05), "{up:?}");
        let down = sh.segments(at(2_500.0), -Vec3::Y, 1e6);
        let (a, b) = span(&down, 0);
        assert!(close(a, 0.0, 1e-3) && close(b, 1_000.0, 0.05), "{down:?}");
        assert!(
            down.spans[1].is_none(),
            "the ground stops the second crossing"
        );
        // Horizontal from inside: one long span to the top of the shell.
        let flat = sh.segments(at(2_500.0), Vec3::Z, 1e7);
        let d = (((R as f64 + 4_000.0).powi(2) - (R as f64 + 2_500.0).powi(2)).sqrt()) as f32;
        assert!(close(span(&flat, 0).1, d, 2.0));
    }

    #[test]
    fn above_the_layer() {
        let sh = shell();
        let down = sh.segments(at(8_000.0), -Vec3::Y, 1e6);
        let (a, b) = span(&down, 0);
        assert!(
            close(a, 4_000.0, 0.05) && close(b, 6_500.0, 0.05),
            "{down:?}"
        );
        assert!(sh.segments(at(8_000.0), Vec3::Y, 1e6).is_empty());
        assert!(sh.segments(at(8_000.0), Vec3::X, 1e7).is_empty());
    }

    #[test]
    fn above_the_layer_grazing_crosses_twice() {
        // A ray from 8 km whose closest approach to the planet center is R + 1 000 m: below the
        // layer but above the ground, so it crosses the shell on the way down and on the way up.
        let sh = shell();
        let (rf, h0) = (R as f64, 8_000.0f64);
        let r_min = rf + 1_000.0;
        let r0 = rf + h0;
        // Direction tilted below horizontal by angle β with sin(β) = ... from r0 cos(β) = r_min.
        let cos_b = r_min / r0;
        let sin_b = (1.0 - cos_b * cos_b).sqrt();
        let dir = Vec3::new(cos_b as f32, -sin_b as f32, 0.0);
        let tc = r0 * sin_b; // parameter of the closest approach
        let half = |h: f64| ((rf + h).powi(2) - r_min * r_min).sqrt();
        let s = sh.segments(at(8_000.0), dir, 1e7);
        let (a0, b0) = span(&s, 0);
        let (a1, b1) = span(&s, 1);
        let tol = 3.0;
        assert!(close(a0, (tc - half(4_000.0)) as f32, tol), "{a0}");
        assert!(close(b0, (tc - half(1_500.0)) as f32, tol), "{b0}");
        assert!(close(a1, (tc + half(1_500.0)) as f32, tol), "{a1}");
        assert!(close(b1, (tc + half(4_000.0)) as f32, tol), "{b1}");
    }

    #[test]
    fn inside_looking_slightly_down_misses_the_ground_and_crosses_twice() {
        let sh = shell();
        let dir = Vec3::new(1.0, -0.02, 0.0).normalize();
        let s = sh.segments(at(2_000.0), dir, 1e7);
        assert!(s.spans[0].is_some() && s.spans[1].is_some(), "{s:?}");
        assert_eq!(span(&s, 0).0, 0.0);
    }

    #[test]
    fn max_distance_clips() {
        let s = shell().segments(at(0.0), Vec3::Y, 2_000.0);
        let (a, b) = span(&s, 0);
        assert!(close(a, 1_500.0, 0.05) && b == 2_000.0);
        assert!(shell().segments(at(0.0), Vec3::Y, 1_000.0).is_empty());
    }

    #[test]
    fn works_with_another_up_axis_and_offset_origin() {
        let sh = Shell {
            up: Vec3::Z,
            ..shell()
        };
        let o = Vec3::new(5_000.0, -3_000.0, 0.0);
        let s = sh.segments(o, Vec3::Z, 1e6);
        // The ground below (5 km, -3 km) sits at altitude ≈ -(x²+y²)/2R ≈ -2.7 m: tiny.
        let h = altitude(o, Vec3::Z, R);
        let (a, b) = span(&s, 0);
        assert!(
            close(a, 1_500.0 - h, 0.1) && close(b, 4_000.0 - h, 0.1),
            "{s:?}"
        );
    }
}
