//! Alignment (SPEC §1.2): each contour's anchor is the midpoint of its leftmost and rightmost
//! points; both contours are moved so that their anchors sit on the design's centre.

use glam::DVec2;

use crate::contour::Contour;

/// Midpoint of the segment joining the contour's leftmost (min x) and rightmost (max x) points.
pub fn anchor(contour: &Contour) -> DVec2 {
    let mut left = contour.points[0];
    let mut right = contour.points[0];
    for &p in &contour.points {
        if p.x < left.x {
            left = p;
        }
        if p.x > right.x {
            right = p;
        }
    }
    (left + right) * 0.5
}

/// The contour translated so that its anchor lies at `center`.
pub fn align(contour: &Contour, center: DVec2) -> Contour {
    contour.translated(center - anchor(contour))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchor_of_an_offset_triangle() {
        // Leftmost (0, 0), rightmost (10, 4): anchor (5, 2).
        let c = Contour::from_points(vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(10.0, 4.0),
            DVec2::new(3.0, 9.0),
        ])
        .unwrap();
        assert!(anchor(&c).distance(DVec2::new(5.0, 2.0)) < 1e-12);
        let moved = align(&c, DVec2::new(90.0, 95.0));
        assert!(anchor(&moved).distance(DVec2::new(90.0, 95.0)) < 1e-12);
    }
}
