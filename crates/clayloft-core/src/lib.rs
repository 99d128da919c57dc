//! Clayloft core: from a design file to a single spiral G-code path, without a window.
pub mod align;
pub mod contour;
pub mod design;
pub mod geometry;
pub mod load;
pub mod sample;
pub mod spline;
pub mod validate;
