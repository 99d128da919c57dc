//! Vessels from meshes (SPEC §15), end to end through the session: a mesh of revolution sliced
//! to rings of the right radius, and the mesh `clayloft stl` writes sliced back to the same wall.

use std::path::Path;

use clayloft_core::design::Design;
use clayloft_core::load::parse_design;
use clayloft_core::stl::{Mesh, job_mesh, write_binary_stl};
use glam::DVec2;

fn solid_of_revolution(n: usize, rings: usize, h: f64, r: impl Fn(f64) -> f64) -> Mesh {
    clayloft_core::mesh::revolution(n, rings, h, r)
}

fn write_stl(mesh: &Mesh, path: &Path) {
    let mut bytes = Vec::new();
    write_binary_stl(mesh, "vessel", &mut bytes).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// A design taking its shape from the mesh at `path`, with `printer` lines appended.
fn mesh_design(path: &Path, extra: &str) -> Design {
    let mut d = parse_design(&format!(
        "version = 1\n[shape.mesh]\npath = {:?}\n{extra}",
        path.display().to_string()
    ))
    .expect("a mesh design");
    d.base_dir = path.parent().map(Path::to_path_buf);
    d
}

/// Distance from `p` to the closed polyline `ring` (XY).
fn distance_to_ring(p: DVec2, ring: &[DVec2]) -> f64 {
    (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            p.distance(a + (b - a) * t)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_bellied_vase_slices_to_rings_half_a_bead_inside_its_surface() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("belly.stl");
    let (h, r) = (60.0, |z: f64| {
        30.0 + 6.0 * (std::f64::consts::PI * z / 60.0).sin()
    });
    write_stl(&solid_of_revolution(256, 241, h, r), &path);
    let design = mesh_design(&path, "");
    let job = clayloft_core::run(&design).expect("the vase prints");
    let s = &job.surface;
    let w = design.printer.line_width;
    assert_eq!(s.layers, (h / design.printer.layer_height).round() as usize);
    let mut worst: f64 = 0.0;
    for (k, section) in s.sections.iter().enumerate().skip(1) {
        let z = k as f64 * s.layer_pitch;
        for p in &section.points {
            let radius = (p.truncate() - s.center).length();
            worst = worst.max((radius - (r(z) - w / 2.0)).abs());
        }
    }
    assert!(
        worst < 0.1,
        "rings off the surface less half a bead by {worst:.3} mm"
    );
    // One continuous path, the base included, that the checker passes.
    assert!(job.toolpath.points.len() > s.sections.len() * design.shape.samples);
    assert!(
        job.findings().all(|f| f.corrected),
        "{:?}",
        job.findings().collect::<Vec<_>>()
    );
}

#[test]
fn the_mesh_clayloft_writes_slices_back_to_the_same_wall() {
    let source =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/designs/flared-bowl.toml");
    let lofted = clayloft_core::load::load_design(&source).unwrap().design;
    let job = clayloft_core::run(&lofted).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bowl.stl");
    write_stl(&job_mesh(&lofted, &job), &path);
    let mut from_mesh = lofted.clone();
    from_mesh.shape.mesh = Some(clayloft_core::design::MeshSource {
        path: path.clone(),
        scale: 1.0,
        rotate_x: 0.0,
    });
    from_mesh.shape.lower = clayloft_core::design::ContourSpec::missing();
    from_mesh.shape.upper = clayloft_core::design::ContourSpec::missing();
    let again = clayloft_core::run(&from_mesh).expect("the bowl's own mesh prints");
    let (a, b) = (&job.surface, &again.surface);
    assert_eq!(a.layers, b.layers, "the same layers");
    let mut worst: f64 = 0.0;
    for (sa, sb) in a.sections.iter().zip(&b.sections).skip(1) {
        let ring = sa.xy();
        for p in &sb.points {
            worst = worst.max(distance_to_ring(p.truncate(), &ring));
        }
    }
    assert!(worst < 0.05, "the wall moved by {worst:.3} mm");
}

#[test]
fn bad_meshes_are_design_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    // Truncated: a binary header announcing more triangles than follow.
    let path = dir.path().join("cut.stl");
    let mut bytes = Vec::new();
    write_binary_stl(
        &solid_of_revolution(16, 3, 20.0, |_| 10.0),
        "cut",
        &mut bytes,
    )
    .unwrap();
    bytes.truncate(bytes.len() - 30);
    std::fs::write(&path, &bytes).unwrap();
    let e = clayloft_core::run(&mesh_design(&path, "")).unwrap_err();
    assert_eq!(e.field, "shape.mesh.path");
    assert!(
        e.message.contains("cut.stl") && e.message.contains("truncated"),
        "{e}"
    );
    // Missing.
    let e = clayloft_core::run(&mesh_design(&dir.path().join("none.stl"), "")).unwrap_err();
    assert!(
        e.message.contains("none.stl") && e.message.contains("cannot read"),
        "{e}"
    );
    // Larger than the bed.
    let path = dir.path().join("big.stl");
    write_stl(&solid_of_revolution(32, 3, 20.0, |_| 400.0), &path);
    let e = clayloft_core::run(&mesh_design(&path, "")).unwrap_err();
    assert!(e.to_string().contains("bed"), "{e}");
    // A rod thinner than a bead: nothing is left half a bead inside it.
    let path = dir.path().join("rod.stl");
    write_stl(&solid_of_revolution(24, 3, 30.0, |_| 1.2), &path);
    let e = clayloft_core::run(&mesh_design(&path, "")).unwrap_err();
    assert!(
        e.message.contains("rod.stl") && e.message.contains("narrower than a bead"),
        "{e}"
    );
    // Scaled to nothing; control lines, which do not apply to a mesh.
    let mut d = mesh_design(&path, "");
    d.shape.mesh.as_mut().unwrap().scale = 0.0;
    assert_eq!(
        clayloft_core::run(&d).unwrap_err().field,
        "shape.mesh.scale"
    );
    let mut d = mesh_design(&path, "");
    d.control
        .vertical
        .push(clayloft_core::design::VerticalLine {
            points: vec![[0.0, 1.0], [1.0, 0.0]],
            angle: None,
            width: None,
        });
    assert_eq!(clayloft_core::run(&d).unwrap_err().field, "control");
    // A design with neither contours nor a mesh.
    let e = parse_design("version = 1\n[shape]\nheight = 50.0\n").unwrap_err();
    assert!(format!("{e:?}").contains("shape.lower"), "{e:?}");
}

#[test]
fn an_obj_mesh_prints_like_the_same_stl() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = solid_of_revolution(64, 31, 40.0, |z| 25.0 + 3.0 * (z / 40.0).sin());
    let stl = dir.path().join("v.stl");
    write_stl(&mesh, &stl);
    let obj = dir.path().join("v.obj");
    let mut text = String::from("o vase\n");
    for v in &mesh.vertices {
        text += &format!("v {} {} {}\n", v.x as f32, v.y as f32, v.z as f32);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(&obj, text).unwrap();
    let (a, b) = (
        clayloft_core::run(&mesh_design(&stl, "")).unwrap(),
        clayloft_core::run(&mesh_design(&obj, "")).unwrap(),
    );
    assert_eq!(a.surface.layers, b.surface.layers);
    for (sa, sb) in a.surface.sections.iter().zip(&b.surface.sections) {
        for (p, q) in sa.points.iter().zip(&sb.points) {
            assert!(p.distance(*q) < 1e-4, "{p} vs {q}");
        }
    }
}

#[test]
fn at_a_sharp_corner_the_bead_stays_inside_the_model() {
    // A box 60 × 60 × 30 mm: its corners are sharper than any bead can follow.
    let mut m = Mesh::default();
    for z in [0.0, 30.0] {
        for (x, y) in [(-30.0, -30.0), (30.0, -30.0), (30.0, 30.0), (-30.0, 30.0)] {
            m.vertices.push(glam::DVec3::new(x, y, z));
        }
    }
    for i in 0..4u32 {
        let j = (i + 1) % 4;
        m.triangles.push([i, j, j + 4]);
        m.triangles.push([i, j + 4, i + 4]);
    }
    m.triangles
        .extend([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.stl");
    write_stl(&m, &path);
    let design = mesh_design(&path, "");
    let job = clayloft_core::run(&design).expect("the box prints");
    let half = design.printer.line_width / 2.0;
    let s = &job.surface;
    let mut nearest = f64::INFINITY;
    for section in s.sections.iter().skip(1) {
        for p in &section.points {
            let q = p.truncate() - s.center;
            // Distance from the path to the box's side: the bead's outside is half a bead out.
            let to_side = (30.0 - q.x.abs()).min(30.0 - q.y.abs());
            nearest = nearest.min(to_side);
            assert!(
                to_side <= half + 0.01
                    || (q.x.abs() > 30.0 - 2.0 * half && q.y.abs() > 30.0 - 2.0 * half),
                "off the side away from a corner: {to_side} at {q}"
            );
        }
    }
    assert!(
        nearest >= half - 0.01,
        "the bead pokes {:.3} mm out of the model",
        half - nearest
    );
}
