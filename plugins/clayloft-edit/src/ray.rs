//! Pointer-ray geometry for dragging: where a ray meets a plane, and which point of an axis
//! line is nearest a ray.

use bevy::math::Vec3;

/// Distance t along the ray `o + t·d` to the plane through `p` with normal `n`; `None` when the
/// ray is parallel to the plane or the plane is behind the eye.
pub fn ray_plane(o: Vec3, d: Vec3, p: Vec3, n: Vec3) -> Option<f32> {
    let denom = d.dot(n);
    if denom.abs() < 1e-6 {
        return None;
    }
    let t = (p - o).dot(n) / denom;
    (t >= 0.0).then_some(t)
}

/// Parameter s of the point `p + s·a` (a unit) of an axis line nearest the ray `o + t·d`
/// (d unit): minimises the distance between the two lines,
/// `s = (a·w − (a·d)(d·w)) / (1 − (a·d)²)` with `w = o − p`.
/// `None` when the ray runs along the axis.
pub fn ray_axis(o: Vec3, d: Vec3, p: Vec3, a: Vec3) -> Option<f32> {
    let w = o - p;
    let b = a.dot(d);
    let denom = 1.0 - b * b;
    if denom < 1e-6 {
        return None;
    }
    Some((a.dot(w) - b * d.dot(w)) / denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_ground_plane() {
        let t = ray_plane(Vec3::new(1.0, 10.0, 2.0), -Vec3::Y, Vec3::ZERO, Vec3::Y).unwrap();
        assert_eq!(t, 10.0);
        assert_eq!(ray_plane(Vec3::Y, Vec3::X, Vec3::ZERO, Vec3::Y), None);
        assert_eq!(ray_plane(Vec3::Y, Vec3::Y, Vec3::ZERO, Vec3::Y), None);
    }

    #[test]
    fn nearest_point_on_axis() {
        // Ray straight down at x = 3 over the x axis: nearest axis point is x = 3.
        let s = ray_axis(Vec3::new(3.0, 5.0, 0.0), -Vec3::Y, Vec3::ZERO, Vec3::X).unwrap();
        assert!((s - 3.0).abs() < 1e-6);
        // An oblique ray crossing above the axis at x = −2.
        let d = Vec3::new(0.0, -1.0, 1.0).normalize();
        let s = ray_axis(Vec3::new(-2.0, 4.0, -4.0), d, Vec3::ZERO, Vec3::X).unwrap();
        assert!((s + 2.0).abs() < 1e-5);
        assert_eq!(ray_axis(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X), None);
    }
}
