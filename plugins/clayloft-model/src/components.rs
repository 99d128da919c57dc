//! The components of the model's entities. They hold data; the systems derive it.

use std::sync::Arc;

use bevy::math::{DVec2, DVec3};
use bevy::prelude::*;
use clayloft_core::pipeline::Surface;
use clayloft_core::section::Section;
use clayloft_core::toolpath::Toolpath;

/// Which of the two contours an entity is.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContourRole {
    /// At z = 0, on the bed.
    Lower,
    /// At z = height, the rim.
    Upper,
}

impl ContourRole {
    pub const BOTH: [ContourRole; 2] = [ContourRole::Lower, ContourRole::Upper];
    /// The contour's index in the core's session (`Session::contour`).
    pub fn index(self) -> usize {
        match self {
            ContourRole::Lower => 0,
            ContourRole::Upper => 1,
        }
    }

    /// Field path of the contour in the design file.
    pub fn field(self) -> &'static str {
        match self {
            ContourRole::Lower => "shape.lower",
            ContourRole::Upper => "shape.upper",
        }
    }
}

/// A contour's samples by arc length and the translation alignment gave it.
#[derive(Component, Debug, Clone, Default)]
pub struct ContourSamples {
    pub samples: Vec<DVec2>,
    /// Spec coordinates + offset = bed coordinates.
    pub offset: DVec2,
}

/// Section k of the surface (k = 0 on the bed .. = layers at the rim).
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SectionIndex(pub usize);

/// The shaped section (loft + control lines, before constraints and texture), shared with the
/// session.
#[derive(Component, Debug, Clone, Default)]
pub struct ShapedSection(pub std::sync::Arc<Section>);

/// Marker of the vessel entity.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Vessel;

/// The corrected, textured surface: what is printed.
#[derive(Component, Debug, Clone)]
pub struct VesselSurface(pub Arc<Surface>);

/// The wall's mesh for the view (the core's [`clayloft_core::view_mesh`], a stage of the
/// session), on the vessel entity: shared by the 3D view and the replay.
#[derive(Component, Debug, Clone)]
pub struct VesselMesh(pub Arc<clayloft_core::view_mesh::WallBuffers>);

/// The wall's inner beads (SPEC §13), on the vessel entity: `[j − 1][k]` is bead `j`'s section
/// `k`; empty for a one-bead wall.
#[derive(Component, Debug, Clone, Default)]
pub struct VesselBeads(pub Arc<clayloft_core::walls::InnerBeads>);

impl VesselBeads {
    /// The innermost bead's sections, if the wall has more than one bead.
    pub fn innermost(&self) -> Option<&[Section]> {
        self.0.last().map(Vec::as_slice)
    }
}

/// The single spiral toolpath.
#[derive(Component, Debug, Clone)]
pub struct ToolpathPath(pub Arc<Toolpath>);

/// Whether the wet wall of the toolpath stands while it is printed (SPEC §14), on the toolpath
/// entity: the session's verdict, redone for a new toolpath or clay body.
#[derive(Component, Debug, Clone)]
pub struct ToolpathPrintability(pub Arc<clayloft_core::printability::Printability>);

/// Which kind of control line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LineKind {
    Vertical,
    Horizontal,
}

/// A control line of the design (`control.vertical[index]` or `control.horizontal[index]`).
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ControlLine {
    pub kind: LineKind,
    pub index: usize,
}

/// The control line drawn on the surface, design space.
#[derive(Component, Debug, Clone, Default)]
pub struct ControlLineCurve(pub Vec<DVec3>);

/// An editable point; its role says which design value it stands for.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EditHandle(pub crate::handles::HandleRole);

/// Where a handle sits, design space (mm); derived from the design.
#[derive(Component, Debug, Clone, Copy, PartialEq, Default)]
pub struct HandlePosition(pub DVec3);
