//! Clayloft core: from a design file to a single spiral G-code path, without a window.
//!
//! The pipeline, in order (each stage a function from plain data to plain data):
//! 1. [`load`] reads and [`validate`]s a [`design::Design`] (SPEC §6; each number's range,
//!    unit and meaning once, in [`fields`]), with the printer
//!    [`profile`] it names (SPEC §12);
//! 2. [`contour`] builds the two closed curves ([`spline`] for user splines, [`trace`] for
//!    pictures, [`svg`] for drawings, through [`outline`]), [`align`] puts their
//!    anchors on the design centre, [`sample`] samples them by arc length and corresponds them;
//! 3. [`loft`] interpolates between them, [`shape`] adds the [`control`] lines section by
//!    [`section`] on a layer plan that keeps layer heights printable;
//! 4. [`constraint`] corrects the overhang locally and [`report`]s each correction;
//! 5. [`texture`] embeds the periodic waves within the same limits;
//! 6. [`toolpath`] joins the sections into one spiral (with a [`base_fill`] under it and, for a
//!    wall of several beads, the [`walls`] inward of the surface), [`gcode`] writes it between the
//!    dialect's [`templates`] with the host metadata and a [`thumbnail`], timed by [`motion`]
//!    as firmware plans it, its numbers written (and read back) by [`decimal`]; [`stl`] meshes
//!    the wall; [`check`] re-measures any G-code file against the printer's limits.
//!
//! [`pipeline`] is the loop over these stages; [`session`] runs them incrementally, redoing only
//! what an edit changed.
pub mod align;
pub mod atomic;
pub mod base_fill;
pub mod check;
pub mod clay;
pub mod constraint;
pub mod contour;
pub mod control;
pub mod decimal;
pub mod design;
pub mod export;
pub mod fields;
pub mod gcode;
pub mod geometry;
pub mod heap;
pub mod interp;
pub mod load;
pub mod loft;
pub mod mesh;
pub mod motion;
pub mod outline;
pub mod parallel;
pub mod pipeline;
pub mod printability;
pub mod profile;
pub mod report;
pub mod sample;
pub mod save;
pub mod seam;
pub mod section;
pub mod session;
pub mod shape;
pub mod spline;
pub mod stl;
pub mod svg;
pub mod templates;
#[cfg(test)]
mod test_rng;
pub mod texture;
pub mod thumbnail;
pub mod toolpath;
pub mod trace;
pub mod validate;
pub mod view_mesh;
pub mod walls;

pub use design::Design;
pub use load::{DesignError, LoadedDesign, load_design};
pub use pipeline::{PrintJob, run};
pub use session::Session;
