//! A section: one closed ring of the surface, `samples` points with their own z (non-planar layers
//! have a z per point). Section k of a surface with L layers sits at height fraction t = k / L.

use glam::{DVec2, DVec3};

/// One ring of surface points, counter-clockwise.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Section {
    pub points: Vec<DVec3>,
}

impl Section {
    /// The XY projection of the ring.
    pub fn xy(&self) -> Vec<DVec2> {
        self.points.iter().map(|p| p.truncate()).collect()
    }

    /// Outward unit normals in XY: [`crate::geometry::outward_normals`] of [`Section::xy`], without making the
    /// XY copy (the overhang clamp and the metrics ask for every section's).
    pub fn normals(&self) -> Vec<DVec2> {
        let (p, n) = (&self.points, self.points.len());
        (0..n)
            .map(|i| {
                let (before, after) = crate::geometry::ring_neighbours(i, n);
                crate::geometry::normal_from_neighbours(p[before].truncate(), p[after].truncate())
            })
            .collect()
    }

    /// Lowest and highest z on the ring.
    pub fn z_range(&self) -> (f64, f64) {
        self.points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.z), hi.max(p.z))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same normals, to the bit, as each XY point's alone (one, two and many points).
    #[test]
    fn normals_are_those_of_the_xy_outline() {
        for n in [1usize, 2, 3, 7, 360] {
            let s = Section {
                points: (0..n)
                    .map(|i| {
                        let t = i as f64 * 2.399;
                        DVec3::new(30.0 * t.cos() + t.sin(), 20.0 * t.sin(), 0.1 * t)
                    })
                    .collect(),
            };
            let ours: Vec<[u64; 2]> = s
                .normals()
                .iter()
                .map(|v| v.to_array().map(f64::to_bits))
                .collect();
            let xy: Vec<[u64; 2]> = (0..n)
                .map(|i| crate::geometry::outward_normal_at(&s.xy(), i))
                .map(|v| v.to_array().map(f64::to_bits))
                .collect();
            let outline: Vec<[u64; 2]> = crate::geometry::outward_normals(&s.xy())
                .iter()
                .map(|v| v.to_array().map(f64::to_bits))
                .collect();
            assert_eq!(ours, xy, "{n} points");
            assert_eq!(outline, xy, "{n} points");
        }
    }
}
