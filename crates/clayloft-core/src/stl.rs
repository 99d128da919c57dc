//! STL export (SPEC §7): the printed wall as a closed 2-manifold mesh — the outer bead's surface
//! offset outward by line_width / 2 along the XY normal, the innermost bead's (the same surface
//! for a one-bead wall, SPEC §13) inward by as much, closed by the rim on top and by the base (a
//! solid disk `base_layers` thick) or, with an open bottom, by an annulus on the bed.

use std::io::{self, Write};

use glam::{DVec3, Vec3};

use crate::design::Design;
use crate::pipeline::{PrintJob, Surface};
use crate::section::Section;

/// A triangle mesh: vertices and counter-clockwise (outward-facing) triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Enclosed volume, mm³, by the divergence theorem: Σ a·(b × c)/6 over the triangles (positive
    /// for a closed mesh with outward-facing triangles).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }
}

/// The closed mesh of a job's printed wall, all its beads.
pub fn job_mesh(design: &Design, job: &PrintJob) -> Mesh {
    let innermost = job.beads.last().map(Vec::as_slice);
    wall_mesh(
        &job.surface,
        innermost,
        design.printer.line_width,
        design.shape.base_layers,
    )
}

/// Builds the closed mesh of the printed wall: the outside from `surface`, the inside from the
/// `innermost` bead's sections (the surface itself when `None`).
pub fn wall_mesh(
    surface: &Surface,
    innermost: Option<&[Section]>,
    line_width: f64,
    base_layers: usize,
) -> Mesh {
    let half = line_width / 2.0;
    let sections = &surface.sections;
    let inside = innermost.unwrap_or(sections);
    let layers = sections.len() - 1;
    let n = sections[0].points.len();
    let base = base_layers.min(layers.saturating_sub(1));
    let mut m = Mesh::default();
    let ring = |m: &mut Mesh, k: usize, sign: f64| -> u32 {
        let start = m.vertices.len() as u32;
        let s = if sign > 0.0 { &sections[k] } else { &inside[k] };
        for (p, nrm) in s.points.iter().zip(s.normals()) {
            let z = if k == 0 { 0.0 } else { p.z };
            m.vertices.push(DVec3::new(
                p.x + sign * half * nrm.x,
                p.y + sign * half * nrm.y,
                z,
            ));
        }
        start
    };
    let outer: Vec<u32> = (0..=layers).map(|k| ring(&mut m, k, 1.0)).collect();
    let inner: Vec<u32> = (base..=layers).map(|k| ring(&mut m, k, -1.0)).collect();
    let nn = n as u32;
    let idx = |start: u32, i: usize| start + (i as u32 % nn);
    let quad = |m: &mut Mesh, a: u32, b: u32, c: u32, d: u32| {
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    };
    for k in 0..layers {
        for i in 0..n {
            let (o0, o1) = (outer[k], outer[k + 1]);
            quad(
                &mut m,
                idx(o0, i),
                idx(o0, i + 1),
                idx(o1, i + 1),
                idx(o1, i),
            );
        }
    }
    for k in 0..inner.len() - 1 {
        for i in 0..n {
            let (i0, i1) = (inner[k], inner[k + 1]);
            quad(
                &mut m,
                idx(i0, i),
                idx(i1, i),
                idx(i1, i + 1),
                idx(i0, i + 1),
            );
        }
    }
    // Rim, facing up.
    let (ot, it) = (outer[layers], inner[inner.len() - 1]);
    for i in 0..n {
        quad(
            &mut m,
            idx(ot, i),
            idx(ot, i + 1),
            idx(it, i + 1),
            idx(it, i),
        );
    }
    if base == 0 {
        // Open bottom: annulus on the bed, facing down.
        let (ob, ib) = (outer[0], inner[0]);
        for i in 0..n {
            quad(
                &mut m,
                idx(ob, i),
                idx(ib, i),
                idx(ib, i + 1),
                idx(ob, i + 1),
            );
        }
    } else {
        let c = surface.center;
        let bottom = m.vertices.len() as u32;
        m.vertices.push(DVec3::new(c.x, c.y, 0.0));
        let top = m.vertices.len() as u32;
        let base_top_z = sections[base].points.iter().map(|p| p.z).sum::<f64>() / n as f64;
        m.vertices.push(DVec3::new(c.x, c.y, base_top_z));
        for i in 0..n {
            m.triangles
                .push([bottom, idx(outer[0], i + 1), idx(outer[0], i)]);
            m.triangles
                .push([top, idx(inner[0], i), idx(inner[0], i + 1)]);
        }
    }
    m
}

fn facet_normal(m: &Mesh, t: &[u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| m.vertices[i as usize]);
    (b - a).cross(c - a).normalize_or_zero().as_vec3()
}

/// Binary STL: 80-byte header, triangle count, then per triangle normal, three vertices and a
/// zero attribute word (all little-endian f32 / u32 / u16).
pub fn write_binary_stl(mesh: &Mesh, name: &str, out: &mut dyn Write) -> io::Result<()> {
    let mut header = [b' '; 80];
    let label = format!("Clayloft STL: {name}");
    let len = label.len().min(80);
    header[..len].copy_from_slice(&label.as_bytes()[..len]);
    out.write_all(&header)?;
    out.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
    let mut buf = Vec::with_capacity(50 * 1024);
    for t in &mesh.triangles {
        let n = facet_normal(mesh, t);
        for v in [n.x, n.y, n.z] {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        for &i in t {
            let v = mesh.vertices[i as usize].as_vec3();
            for c in [v.x, v.y, v.z] {
                buf.extend_from_slice(&c.to_le_bytes());
            }
        }
        buf.extend_from_slice(&0u16.to_le_bytes());
        if buf.len() >= 50 * 1000 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)
}

/// ASCII STL.
pub fn write_ascii_stl(mesh: &Mesh, name: &str, out: &mut dyn Write) -> io::Result<()> {
    let name: String = name
        .chars()
        .filter(|c| c.is_ascii_graphic() || *c == ' ')
        .collect();
    writeln!(out, "solid {name}")?;
    for t in &mesh.triangles {
        let n = facet_normal(mesh, t);
        writeln!(out, "  facet normal {:e} {:e} {:e}", n.x, n.y, n.z)?;
        writeln!(out, "    outer loop")?;
        for &i in t {
            let v = mesh.vertices[i as usize].as_vec3();
            writeln!(out, "      vertex {:e} {:e} {:e}", v.x, v.y, v.z)?;
        }
        writeln!(out, "    endloop")?;
        writeln!(out, "  endfacet")?;
    }
    writeln!(out, "endsolid {name}")
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Every undirected edge is used by exactly two triangles, once in each direction.
    pub fn assert_closed_manifold(m: &Mesh) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(
                count, 1,
                "edge {a}->{b} used {count} times in one direction"
            );
            assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    fn surface(base: usize) -> (crate::design::Design, Surface) {
        let d = crate::load::parse_design(&format!(
            "version = 1\n[shape]\nheight = 10.0\nsamples = 400\nbase_layers = {base}\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n"
        ))
        .unwrap();
        let s = crate::pipeline::build_surface(&d).unwrap();
        (d, s)
    }

    #[test]
    fn open_cylinder_wall_is_closed_with_the_tube_volume() {
        let (_, s) = surface(0);
        let m = wall_mesh(&s, None, 3.0, 0);
        assert_closed_manifold(&m);
        // Tube of radii 28.5 and 31.5, 10 mm tall: π(31.5² − 28.5²)·10.
        let expected = std::f64::consts::PI * (31.5f64.powi(2) - 28.5f64.powi(2)) * 10.0;
        assert!(
            (m.volume() - expected).abs() / expected < 1e-3,
            "{}",
            m.volume()
        );
    }

    #[test]
    fn cup_with_base_is_closed_with_the_cup_volume() {
        let (_, s) = surface(2);
        let m = wall_mesh(&s, None, 3.0, 2);
        assert_closed_manifold(&m);
        let expected = std::f64::consts::PI * (31.5f64.powi(2) - 28.5f64.powi(2)) * 8.0
            + std::f64::consts::PI * 31.5f64.powi(2) * 2.0;
        assert!(
            (m.volume() - expected).abs() / expected < 2e-3,
            "{}",
            m.volume()
        );
    }

    #[test]
    fn a_two_bead_wall_is_meshed_two_beads_thick() {
        let (_, s) = surface(0);
        let beads = crate::walls::inner_beads(&s, 2, 3.0, None).unwrap();
        let m = wall_mesh(&s, beads.last().map(Vec::as_slice), 3.0, 0);
        assert_closed_manifold(&m);
        // Tube of radii 31.5 and 30 − 3 − 1.5 = 25.5.
        let expected = std::f64::consts::PI * (31.5f64.powi(2) - 25.5f64.powi(2)) * 10.0;
        assert!(
            (m.volume() - expected).abs() / expected < 1e-3,
            "{}",
            m.volume()
        );
    }

    #[test]
    fn binary_stl_has_the_declared_size() {
        let (_, s) = surface(1);
        let m = wall_mesh(&s, None, 3.0, 1);
        let mut v = Vec::new();
        write_binary_stl(&m, "cup", &mut v).unwrap();
        assert_eq!(v.len(), 84 + 50 * m.triangles.len());
        let mut a = Vec::new();
        write_ascii_stl(&m, "cup", &mut a).unwrap();
        let text = String::from_utf8(a).unwrap();
        assert_eq!(text.matches("facet normal").count(), m.triangles.len());
    }
}
