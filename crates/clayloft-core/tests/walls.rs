//! Walls of several beads end to end (SPEC §13): the shipped two-bead star bowl and a ribbed
//! vase through the whole pipeline, the G-code re-measured by the checker, the clay and the
//! STL against a one-bead wall of the same vessel.

use std::path::Path;

use clayloft_core::check::{Limits, check_gcode};
use clayloft_core::gcode::{summarize, write_gcode};
use clayloft_core::load::load_design;
use clayloft_core::stl::job_mesh;

#[test]
fn the_two_bead_star_bowl_prints_one_checked_path_with_twice_the_wall() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/designs/star-bowl.toml");
    let design = load_design(&path).unwrap().design;
    assert_eq!(design.shape.walls, 2);
    assert!(design.shape.wall_ties);
    // Tied and untied (long straight inner edges: the checker measures to the segments, not to
    // their lines extended past a star's tips).
    let mut untied = design.clone();
    untied.shape.wall_ties = false;
    for d in [&design, &untied] {
        let job = clayloft_core::run(d).unwrap();
        assert_eq!(job.beads.len(), 1);
        let mut text = Vec::new();
        write_gcode(d, &job, &mut text).unwrap();
        let report = check_gcode(
            std::str::from_utf8(&text).unwrap(),
            &Limits::from(&d.printer),
        )
        .unwrap();
        assert!(
            report.ok(),
            "ties {}: {:?}",
            d.shape.wall_ties,
            report.violations
        );
    }
    let job = clayloft_core::run(&design).unwrap();

    // The same vessel with one bead, ties off.
    let mut one = design.clone();
    one.shape.walls = 1;
    one.shape.wall_ties = false;
    let single = clayloft_core::run(&one).unwrap();
    // The base is the same; the wall's clay about doubles (the inner bead is shorter round a
    // flaring star, the ties make it longer).
    let (v2, v1) = (
        summarize(&design, &job).volume_mm3,
        summarize(&one, &single).volume_mm3,
    );
    assert!(v2 > 1.6 * v1 && v2 < 2.1 * v1, "{v2} vs {v1}");
    // The STL's wall is thicker by the inner bead.
    let (m2, m1) = (job_mesh(&design, &job), job_mesh(&one, &single));
    let (v2, v1) = (m2.volume(), m1.volume());
    assert!(v2 > 1.5 * v1, "{v2} {v1}");
}

#[test]
fn three_beads_on_a_textured_vase_pass_the_checker() {
    let text = "version = 1\n[shape]\nheight = 40.0\nsamples = 240\nbase_layers = 2\nwalls = 3\n\
        [shape.lower]\ntype = \"circle\"\nradius = 35.0\n[shape.upper]\ntype = \"circle\"\nradius = 45.0\n\
        [texture.x]\nwave = \"sine\"\nperiod = 12\namplitude = 1.5\n";
    let design = clayloft_core::load::parse_design(text).unwrap();
    let job = clayloft_core::run(&design).unwrap();
    assert_eq!(job.beads.len(), 2);
    let mut out = Vec::new();
    write_gcode(&design, &job, &mut out).unwrap();
    let report = check_gcode(
        std::str::from_utf8(&out).unwrap(),
        &Limits::from(&design.printer),
    )
    .unwrap();
    assert!(report.ok(), "{:?}", report.violations);
}

#[test]
fn too_many_beads_for_the_vessel_say_where() {
    let text = "version = 1\n[shape]\nheight = 20.0\nwalls = 3\n\
        [shape.lower]\ntype = \"ellipse\"\nrx = 40.0\nry = 6.0\n[shape.upper]\ntype = \"ellipse\"\nrx = 40.0\nry = 6.0\n";
    let design = clayloft_core::load::parse_design(text).unwrap();
    let e = clayloft_core::run(&design).unwrap_err();
    assert_eq!(e.field, "shape.walls");
    assert!(e.message.contains("narrower than 3 beads"), "{e}");
    for (bad, why) in [
        ("walls = 4", "shape.walls"),
        ("walls = 0", "shape.walls"),
        ("wall_ties = true", "shape.wall_ties"),
    ] {
        let t = format!(
            "version = 1\n[shape]\nheight = 20.0\n{bad}\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n"
        );
        let e = clayloft_core::load::parse_design(&t)
            .map_err(|e| format!("{e:?}"))
            .and_then(|d| clayloft_core::run(&d).map_err(|e| e.to_string()))
            .unwrap_err();
        assert!(e.contains(why), "{bad}: {e}");
    }
}
