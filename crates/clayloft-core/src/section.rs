//! A section: one closed ring of the surface, `samples` points with their own z (non-planar layers
//! have a z per point). Section k of a surface with L layers sits at height fraction t = k / L.

use glam::{DVec2, DVec3};

use crate::geometry::outward_normals;

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

    /// Outward unit normals in XY.
    pub fn normals(&self) -> Vec<DVec2> {
        outward_normals(&self.xy())
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
