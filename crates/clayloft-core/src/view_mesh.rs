//! The wall as a triangle mesh for a 3D view, coloured by how far each point leans from
//! vertical (the overhang of SPEC §2): plain buffers, built by the [`crate::session::Session`]
//! beside the path's stages, so that the app's view and replay share one copy and the
//! benchmarks and tests need no GPU.
//!
//! Positions and normals are in the view frame `(x, z, −y)`: y up, as glTF and most 3D engines
//! (Bevy among them) have it; a right-handed rotation of the design's z-up frame, so the vessel
//! stands on the bed the way it prints.

use glam::{DVec3, Vec3};

use crate::pipeline::Surface;
use crate::section::Section;

/// A design-space point (mm, z up) in the view frame (y up).
#[inline]
pub fn to_view(p: DVec3) -> Vec3 {
    Vec3::new(p.x as f32, p.z as f32, -p.y as f32)
}

/// A view-frame point back in design space.
#[inline]
pub fn from_view(w: Vec3) -> DVec3 {
    DVec3::new(w.x as f64, -w.z as f64, w.y as f64)
}

/// Vertex and index buffers of the wall, in the view frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WallBuffers {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub colors: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
    /// Points whose lean exceeds the limit.
    pub violating: usize,
    /// Indices of one row of quads (between sections k and k + 1), all sheets.
    pub indices_per_row: usize,
}

const CLAY: [f32; 3] = [0.80, 0.52, 0.38];
const AMBER: [f32; 3] = [0.95, 0.75, 0.20];
const RED: [f32; 4] = [0.90, 0.08, 0.08, 1.0];

/// Clay blended towards amber by `w` in 0 … 1.
fn clay_to_amber(w: f32) -> [f32; 4] {
    let mix = |a: f32, b: f32| a + (b - a) * w;
    [
        mix(CLAY[0], AMBER[0]),
        mix(CLAY[1], AMBER[1]),
        mix(CLAY[2], AMBER[2]),
        1.0,
    ]
}

/// Colour of a wall point leaning `lean` degrees when the limit is `limit` degrees: clay when
/// upright, through amber towards the limit, red past it.
pub fn lean_color(lean: f32, limit: f32) -> [f32; 4] {
    if lean > limit + 0.5 {
        return RED;
    }
    let f = (lean / limit.max(1e-3)).clamp(0.0, 1.0);
    // Stay clay-coloured up to 60 % of the limit, then blend to amber at the limit.
    clay_to_amber(((f - 0.6) / 0.4).clamp(0.0, 1.0))
}

/// Colour of a wall layer whose safety factor against collapse or buckling is `f` (SPEC §14):
/// clay where it holds with margin (F ≥ 2), through amber towards 1, red where it fails.
pub fn safety_color(f: f64) -> [f32; 4] {
    if f < 1.0 {
        return RED;
    }
    clay_to_amber(((2.0 - f) as f32).clamp(0.0, 1.0))
}

impl WallBuffers {
    /// Recolours the wall by the safety factor of each vertex's layer.
    pub fn colour_by_safety(&mut self, p: &crate::printability::Printability) {
        for (c, pos) in self.colors.iter_mut().zip(&self.positions) {
            // The view's y is the design's z.
            *c = safety_color(p.factor_at(pos[1] as f64));
        }
    }
}

/// Builds the wall buffers: one vertex per surface point, two triangles per quad between
/// consecutive sections (closed around), normals from central differences. With an `innermost`
/// bead (a wall of several beads, SPEC §13) its sheet follows, facing inward and coloured by the
/// outer bead's lean, so the wall shows its thickness; each row's triangles of both sheets are
/// consecutive ([`WallBuffers::indices_per_row`]) so that a replay can show the rows printed.
pub fn wall_buffers(
    surface: &Surface,
    innermost: Option<&[Section]>,
    limit_deg: f64,
) -> WallBuffers {
    let sections = &surface.sections;
    let rows = sections.len();
    let n = sections.first().map_or(0, |s| s.points.len());
    if rows < 2 || n < 3 {
        return WallBuffers::default();
    }
    let innermost = innermost.filter(|b| b.len() == rows && b.iter().all(|s| s.points.len() == n));
    // The surface's own leans (measured once by the core); a surface put together by hand may
    // lack them.
    let computed;
    let leans = if surface.point_leans_deg.len() == rows * n {
        &surface.point_leans_deg
    } else {
        computed = crate::constraint::point_leans_deg(sections);
        &computed
    };
    let limit = limit_deg as f32;
    let sheets: Vec<&[Section]> = std::iter::once(sections.as_slice())
        .chain(innermost)
        .collect();
    let mut b = WallBuffers {
        indices_per_row: sheets.len() * n * 6,
        violating: leans.iter().filter(|a| **a > limit + 0.5).count(),
        ..WallBuffers::default()
    };
    for (sheet, rings) in sheets.iter().enumerate() {
        let outward = if sheet == 0 { 1.0 } else { -1.0 };
        let first = b.positions.len();
        b.positions.extend(
            rings
                .iter()
                .flat_map(|s| s.points.iter().map(|p| to_view(*p).to_array())),
        );
        let sheet_positions = &b.positions[first..first + rows * n];
        let row = |k: usize| &sheet_positions[k * n..(k + 1) * n];
        let mut normals = Vec::with_capacity(rows * n);
        for k in 0..rows {
            let (here, down, up) = (row(k), row(k.saturating_sub(1)), row((k + 1).min(rows - 1)));
            // Central differences around the ring and up the wall; contours run
            // counter-clockwise seen from above: around × up points outward.
            let normal = |before: usize, i: usize, after: usize| {
                let around = Vec3::from_array(here[after]) - Vec3::from_array(here[before]);
                let up = Vec3::from_array(up[i]) - Vec3::from_array(down[i]);
                (outward * around.cross(up).normalize_or_zero()).to_array()
            };
            normals.push(normal(n - 1, 0, 1));
            normals.extend((1..n - 1).map(|i| normal(i - 1, i, i + 1)));
            normals.push(normal(n - 2, n - 1, 0));
        }
        b.normals.extend(normals);
        b.colors.extend(leans.iter().map(|a| lean_color(*a, limit)));
    }
    // Each row's triangles are those of the first row moved on by k·n vertices: the first
    // row's are made once (sheet by sheet) and offset.
    let mut first_row = Vec::with_capacity(b.indices_per_row);
    for sheet in 0..sheets.len() {
        let r0 = (sheet * rows * n) as u32;
        let r1 = r0 + n as u32;
        for i in 0..n as u32 {
            let j = if i + 1 == n as u32 { 0 } else { i + 1 };
            if sheet == 0 {
                first_row.extend_from_slice(&[r0 + i, r0 + j, r1 + j, r0 + i, r1 + j, r1 + i]);
            } else {
                first_row.extend_from_slice(&[r0 + i, r1 + j, r0 + j, r0 + i, r1 + i, r1 + j]);
            }
        }
    }
    b.indices.reserve((rows - 1) * b.indices_per_row);
    for k in 0..rows - 1 {
        let shift = (k * n) as u32;
        b.indices.extend(first_row.iter().map(|v| v + shift));
    }
    if sheets.len() > 1 {
        // The rim between the sheets, facing up (last, so a replay shows it with the top row).
        let top = rows - 1;
        let first = b.positions.len() as u32;
        for sheet in 0..2 {
            for i in 0..n {
                let v = sheet * rows * n + top * n + i;
                b.positions.push(b.positions[v]);
                b.normals.push(Vec3::Y.to_array());
                b.colors.push(b.colors[v]);
            }
        }
        let (o, inner) = (first, first + n as u32);
        for i in 0..n as u32 {
            let j = (i + 1) % n as u32;
            b.indices
                .extend_from_slice(&[o + i, inner + j, inner + i, o + i, o + j, inner + j]);
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_up_axis() {
        let p = DVec3::new(10.0, 20.0, 30.0);
        assert_eq!(from_view(to_view(p)), p);
        assert_eq!(to_view(DVec3::Z), Vec3::Y);
        // x × y = z in design space must stay right-handed in the view: x × (−z) = y.
        assert_eq!(
            to_view(DVec3::X).cross(to_view(DVec3::Y)),
            to_view(DVec3::Z)
        );
    }

    #[test]
    fn colours_run_from_clay_to_red() {
        let close = |a: [f32; 4], b: [f32; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close(lean_color(0.0, 45.0), [0.80, 0.52, 0.38, 1.0]));
        assert!(close(lean_color(20.0, 45.0), [0.80, 0.52, 0.38, 1.0]));
        assert!(close(lean_color(45.0, 45.0), [0.95, 0.75, 0.20, 1.0]));
        assert!(close(lean_color(50.0, 45.0), [0.90, 0.08, 0.08, 1.0]));
    }

    #[test]
    fn a_wall_that_fails_is_red_at_its_foot_and_clay_at_its_rim() {
        assert_eq!(safety_color(0.9), [0.90, 0.08, 0.08, 1.0]);
        assert_eq!(safety_color(2.5), [0.80, 0.52, 0.38, 1.0]);
        assert_eq!(safety_color(1.0), [0.95, 0.75, 0.20, 1.0]);
        let d = crate::load::parse_design(
            "version = 1\n[printer]\nmax_z = 1000.0\n[shape]\nheight = 400.0\nsamples = 60\n\
             lower = { type = \"circle\", radius = 60.0 }\nupper = { type = \"circle\", radius = 60.0 }\n\
             [clay]\nbody = \"porcelain\"\nstructuration_rate = 0.05\n",
        )
        .unwrap();
        let job = crate::run(&d).unwrap();
        let p = crate::printability::assess(&d, &job.surface, &job.toolpath).unwrap();
        assert!(p.factor < 1.0);
        let mut b = wall_buffers(&job.surface, None, 45.0);
        b.colour_by_safety(&p);
        let n = 60;
        assert_eq!(b.colors[n], safety_color(0.0), "the foot fails");
        assert_eq!(
            b.colors[b.colors.len() - 1],
            safety_color(10.0),
            "the rim holds"
        );
    }

    #[test]
    fn cylinder_mesh_has_outward_normals_and_closed_rings() {
        let d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 10.0\nsamples = 36\nbase_layers = 0\n\
             lower = { type = \"circle\", radius = 20.0 }\nupper = { type = \"circle\", radius = 20.0 }\n",
        )
        .unwrap();
        let s = crate::pipeline::build_surface(&d).unwrap();
        let b = wall_buffers(&s, None, 45.0);
        assert_eq!(b.positions.len(), 36 * 11);
        assert_eq!(b.indices.len(), 36 * 10 * 6);
        assert_eq!(b.violating, 0);
        let c = to_view(s.center.extend(0.0));
        for (p, nrm) in b.positions.iter().zip(&b.normals) {
            let radial = (Vec3::from_array(*p) - c).with_y(0.0).normalize();
            assert!(radial.dot(Vec3::from_array(*nrm)) > 0.999, "{p:?} {nrm:?}");
        }
    }

    #[test]
    /// The normals and the triangles are those of the plain loops (each vertex's neighbours
    /// taken round the ring, each row's quads one by one): a textured two-bead wall.
    fn the_buffers_are_the_plain_loops() {
        let d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 20.0\nsamples = 48\nbase_layers = 0\nwalls = 2\n\
             lower = { type = \"rose\", radius = 30.0, amplitude = 3.0, petals = 5 }\n\
             upper = { type = \"circle\", radius = 26.0 }\n\
             [texture]\nx = { wave = \"sine\", period = 10.0, amplitude = 1.0 }\n",
        )
        .unwrap();
        let job = crate::run(&d).unwrap();
        let b = wall_buffers(&job.surface, job.beads.last().map(Vec::as_slice), 45.0);
        let (rows, n) = (job.surface.sections.len(), 48);
        let mut normals = Vec::new();
        let mut indices = Vec::new();
        for (sheet, outward) in [(0, 1.0), (1, -1.0f32)] {
            let at =
                |k: usize, i: usize| Vec3::from_array(b.positions[sheet * rows * n + k * n + i]);
            for k in 0..rows {
                let (kd, ku) = (k.saturating_sub(1), (k + 1).min(rows - 1));
                for i in 0..n {
                    let (before, after) = crate::geometry::ring_neighbours(i, n);
                    let around = at(k, after) - at(k, before);
                    let up = at(ku, i) - at(kd, i);
                    normals.push((outward * around.cross(up).normalize_or_zero()).to_array());
                }
            }
        }
        for k in 0..rows - 1 {
            for sheet in 0..2 {
                let base = sheet * rows * n;
                let (r0, r1) = ((base + k * n) as u32, (base + (k + 1) * n) as u32);
                for i in 0..n as u32 {
                    let j = (i + 1) % n as u32;
                    indices.extend_from_slice(&if sheet == 0 {
                        [r0 + i, r0 + j, r1 + j, r0 + i, r1 + j, r1 + i]
                    } else {
                        [r0 + i, r1 + j, r0 + j, r0 + i, r1 + i, r1 + j]
                    });
                }
            }
        }
        assert_eq!(b.normals[..2 * rows * n], normals[..]);
        assert_eq!(b.indices[..indices.len()], indices[..]);
    }

    #[test]
    fn a_two_bead_wall_shows_an_inner_sheet_facing_inward_a_bead_inside() {
        let d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 10.0\nsamples = 36\nbase_layers = 0\nwalls = 2\n\
             lower = { type = \"circle\", radius = 20.0 }\nupper = { type = \"circle\", radius = 20.0 }\n",
        )
        .unwrap();
        let job = crate::run(&d).unwrap();
        let b = wall_buffers(&job.surface, job.beads.last().map(Vec::as_slice), 45.0);
        // Two sheets and the rim between them.
        assert_eq!(b.positions.len(), 2 * 36 * 11 + 2 * 36);
        assert_eq!(b.indices_per_row, 2 * 36 * 6);
        assert_eq!(b.indices.len(), 10 * b.indices_per_row + 36 * 6);
        let c = to_view(job.surface.center.extend(0.0));
        for (p, nrm) in b.positions[36 * 11..2 * 36 * 11]
            .iter()
            .zip(&b.normals[36 * 11..])
        {
            let off = (Vec3::from_array(*p) - c).with_y(0.0);
            // The sampled circle's offset: within the chord's sagitta of 17 mm.
            assert!((off.length() - 17.0).abs() < 0.1, "{p:?}");
            assert!(
                off.normalize().dot(Vec3::from_array(*nrm)) < -0.999,
                "{nrm:?}"
            );
        }
        // Every triangle winds counter-clockwise (the usual front face) round its vertices'
        // normal: the outside faces out, the inside in, the rim up.
        let v = |i: u32| Vec3::from_array(b.positions[i as usize]);
        for t in b.indices.chunks(3) {
            let face = (v(t[1]) - v(t[0])).cross(v(t[2]) - v(t[0]));
            let nrm = Vec3::from_array(b.normals[t[0] as usize]);
            assert!(face.dot(nrm) > 0.0, "{t:?}");
        }
    }
}
