//! End-to-end tests of printer profiles (SPEC §12): every shipped profile with every shipped
//! design, profile selection and its errors, the printer's own frame, the dialects' start and end
//! G-code, host metadata and thumbnails.

use std::process::Output;

mod common;
use common::{clayloft, text, toml_files};

fn profile_names() -> Vec<String> {
    toml_files("assets/printers")
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// G-code for `design` with `extra` appended to its text (a `[printer]` table) in a temp dir.
fn gcode_with(design: &str, args: &[&str]) -> (Output, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.toml");
    std::fs::write(&path, design).unwrap();
    let out = dir.path().join("o.gcode");
    let mut all = vec!["gcode", path.to_str().unwrap(), "-o", out.to_str().unwrap()];
    all.extend_from_slice(args);
    let run = clayloft(&all);
    let g = std::fs::read_to_string(&out).unwrap_or_default();
    (run, g)
}

const VASE: &str = "version = 1\nname = \"test vase\"\n[shape]\nheight = 40.0\nsamples = 90\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 34.0\n";

#[test]
fn every_profile_with_every_design_checks_or_says_it_does_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let mut printed = 0;
    for design in toml_files("assets/designs") {
        for profile in profile_names() {
            let out = dir.path().join("o.gcode");
            let run = clayloft(&[
                "gcode",
                design.to_str().unwrap(),
                "--printer",
                &profile,
                "-o",
                out.to_str().unwrap(),
            ]);
            let err = text(&run.stderr);
            match run.status.code() {
                Some(0) => {
                    let check = clayloft(&["check", out.to_str().unwrap()]);
                    assert_eq!(
                        check.status.code(),
                        Some(0),
                        "{} on {profile}: {}",
                        design.display(),
                        text(&check.stdout)
                    );
                    printed += 1;
                }
                Some(2) => {
                    assert!(
                        err.contains("does not print on this printer")
                            || err.contains("printer's range")
                            || err.contains("bed")
                            || err.contains("build height"),
                        "{} on {profile}: {err}",
                        design.display()
                    );
                    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
                    assert!(!out.exists(), "no file on error");
                    // The program went to a temporary file on its way through the self-check:
                    // refused, it is gone too.
                    assert_eq!(
                        std::fs::read_dir(dir.path()).unwrap().count(),
                        0,
                        "{} on {profile}: a temporary file was left",
                        design.display()
                    );
                }
                other => panic!("{} on {profile}: exit {other:?}: {err}", design.display()),
            }
            let _ = std::fs::remove_file(&out);
        }
    }
    // 93 of the 104 print (2026-12-05; 75 before the wall left the flat layer as one helix, the
    // outline of the base was laid all round and the checker took a base's step up a layer for
    // what it is; 90 before it took the corner below for what a point past its tip rests on).
    assert!(printed >= 93, "only {printed} combinations print");
}

/// Where the wall leaves the base, on the shipped designs the self-check used to refuse there:
/// a 45° flare over the base's outline (its bridge left a notch: 47.3° on the WASP), an oval
/// jar whose layers are the delta's minimum (the first revolution rose h − a = 0: flat rings
/// joined by steps, each ring's end a layer too thin), and the two-bead star bowl on the Eazao
/// (its first turn rose (h − a)/2 = 0.25 mm over its own start), and the flared bowl's 5 mm
/// beads on the Potterbot (the checker took the base layer a layer's step below for the bead
/// just laid). Each now prints, and `check` accepts the file.
#[test]
fn the_wall_leaves_the_base_on_every_printer_it_fits() {
    let dir = tempfile::tempdir().unwrap();
    for (design, profile) in [
        ("flared-bowl", "wasp-2040-clay"),
        ("flared-bowl", "klipper-paste-delta"),
        ("ellipse-ripple", "klipper-paste-delta"),
        ("star-bowl", "eazao-zero"),
        ("paper-woven", "wasp-40100-ldm"),
        ("flared-bowl", "potterbot-baby"),
    ] {
        let said = prints_and_checks(dir.path(), design, profile);
        // The oval jar's 0.5 mm layers are the delta's minimum: its wall cannot come back onto
        // them once it has left the base, and ends half a millimetre taller, as the summary says.
        if (design, profile) == ("ellipse-ripple", "klipper-paste-delta") {
            assert!(
                said.contains("x 70.5 mm wet")
                    && said.contains("the wall ends up to 0.50 mm above"),
                "{said}"
            );
        }
    }
}

/// `clayloft gcode` of shipped design `design` on shipped printer `profile` into `dir`: it
/// prints, and `clayloft check` accepts the file. What the summary said.
fn prints_and_checks(dir: &std::path::Path, design: &str, profile: &str) -> String {
    common::gcode_and_check(
        &format!("assets/designs/{design}.toml"),
        &["--printer", profile],
        &dir.join(format!("{design}.{profile}.gcode")),
        &format!("{design} on {profile}"),
    )
}

/// The petal vase on the printers of the widest beads: where the belly pushes the wall out of
/// the rose's valleys, the layer below turns a sharp corner (where the shape cuts the fold off;
/// before 2026-12-06 at the tip of a little loop), and the point above lies just past the tip,
/// past the end of both short segments that meet there. The self-check found nothing under it
/// ("unsupported", or resting on the layer under that: "a layer too thick") and refused all
/// three; it now takes the corner for what the point rests on. Each prints, and `check` accepts
/// the file. (With the corner rule switched off, all three are still refused, 2026-12-06: layer
/// too thick at 1–4 points.)
#[test]
fn a_wall_past_the_corners_of_the_layer_below_prints() {
    let dir = tempfile::tempdir().unwrap();
    for profile in ["potterbot-baby", "potterbot-super-10", "wasp-40100-ldm"] {
        prints_and_checks(dir.path(), "petal-vase", profile);
    }
}

#[test]
fn printers_lists_every_shipped_profile() {
    let out = clayloft(&["printers"]);
    assert!(out.status.success());
    let list = text(&out.stdout);
    for name in profile_names() {
        assert!(list.contains(&name), "{name} missing: {list}");
    }
    let wasp = list
        .lines()
        .find(|l| l.starts_with("wasp-2040-clay"))
        .unwrap();
    assert!(
        wasp.contains("round 200") && wasp.contains("centre") && wasp.contains(" delta"),
        "{wasp}"
    );
}

#[test]
fn a_design_names_a_profile_and_its_own_fields_win() {
    let design = VASE.replace(
        "[shape]",
        "[printer]\nprofile = \"eazao-zero\"\nprint_speed = 12.0\n[shape]",
    );
    let (run, g) = gcode_with(&design, &[]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(
        g.contains("; printer: eazao-zero, rectangular bed 150 x 150 mm"),
        "{}",
        &g[..600]
    );
    assert!(g.contains("bed_x=150 bed_y=150 max_z=240 line_width=3"));
    assert!(g.contains(" F720.0"), "the design's 12 mm/s");
    // --printer replaces the design's pick; the design's own speed still wins.
    let (run, g) = gcode_with(&design, &["--printer", "wasp-2040-clay"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(g.contains("; printer: wasp-2040-clay, round bed 200 mm across"));
    assert!(g.contains(" F720.0"));
}

#[test]
fn unknown_profiles_and_bad_profile_files_exit_2_naming_file_line_and_field() {
    let design = VASE.replace(
        "[shape]",
        "[printer]\nprofile = \"no-such-printer\"\n[shape]",
    );
    let (run, _) = gcode_with(&design, &[]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("d.toml:4: printer.profile")
            && err.contains("no-such-printer")
            && err.contains("eazao-zero"),
        "{err}"
    );
    let (run, _) = gcode_with(VASE, &["--printer", "nope"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(text(&run.stderr).contains("\"nope\""));
    // A profile file with an impossible number and one with an unknown field.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("mine.toml");
    std::fs::write(
        &bad,
        "name = \"mine\"\n[printer]\nbed_x = 200.0\nline_width = -3.0\n",
    )
    .unwrap();
    let (run, _) = gcode_with(VASE, &["--printer", bad.to_str().unwrap()]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(err.contains("mine.toml:4: printer.line_width"), "{err}");
    std::fs::write(&bad, "name = \"mine\"\n[printer]\nbed_widht = 200.0\n").unwrap();
    let (run, _) = gcode_with(VASE, &["--printer", bad.to_str().unwrap()]);
    let err = text(&run.stderr);
    assert!(
        err.contains("mine.toml:3:") && err.contains("bed_widht"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// X and Y of every G0/G1 that gives both, as written.
fn xy(g: &str) -> Vec<(f64, f64)> {
    g.lines()
        .filter(|l| l.starts_with("G1 ") || l.starts_with("G0 "))
        .filter_map(|l| {
            let get = |c: char| {
                l.split_whitespace()
                    .find(|w| w.starts_with(c))
                    .and_then(|w| w[1..].parse::<f64>().ok())
            };
            Some((get('X')?, get('Y')?))
        })
        .collect()
}

#[test]
fn a_round_bed_with_its_origin_in_the_centre() {
    let (run, g) = gcode_with(VASE, &["--printer", "wasp-2040-clay"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let pts = xy(&g);
    let (cx, cy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let n = pts.len() as f64;
    // The vessel sits on the bed centre, which is (0, 0) in this printer's frame.
    assert!(
        (cx / n).abs() < 2.0 && (cy / n).abs() < 2.0,
        "{} {}",
        cx / n,
        cy / n
    );
    assert!(pts.iter().any(|p| p.0 < -25.0) && pts.iter().any(|p| p.0 > 25.0));
    // Too wide for the round bed (Ø 200 mm: a 110 mm radius does not fit), though its square
    // bounding box would.
    let wide = VASE
        .replace("radius = 30.0", "radius = 99.8")
        .replace("radius = 34.0", "radius = 99.8");
    let (run, _) = gcode_with(&wide, &["--printer", "wasp-2040-clay"]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(err.contains("round bed's radius is 100"), "{err}");
    // shape.center is in the printer's own frame: (20, 0) is 20 mm right of the centre.
    let moved = VASE.replace("[shape]\n", "[shape]\ncenter = [20.0, 0.0]\n");
    let (run, g) = gcode_with(&moved, &["--printer", "wasp-2040-clay"]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let pts = xy(&g);
    let mean = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
    assert!((mean - 20.0).abs() < 2.0, "{mean}");
}

#[test]
fn the_dialects_start_and_end_gcode_are_pinned() {
    for (dialect, start, end) in [
        (
            "marlin",
            "; start (Marlin, no heating: clay is cold)\nG21 ; millimetres\nG90 ; absolute positions\nG28 ; home\nM83 ; extrusion mode\nM302 P1 ; allow cold extrusion\nG92 E0\n",
            "; end: lift clear of the rim, present the part, motors off\nG90\nG0 Z50.000 F3000\nG0 X0.000 Y190.000 F3000\nM84\n",
        ),
        (
            "klipper",
            "; start (Klipper, no heating: clay is cold; set min_extrude_temp: 0 in printer.cfg)\nG21\nG90\nG28\nM83\nG92 E0\nSET_PRINT_STATS_INFO TOTAL_LAYER=40\n",
            "; end: lift clear of the rim, present the part, motors off\nG90\nG0 Z50.000 F3000\nG0 X0.000 Y190.000 F3000\nM84\n",
        ),
        (
            "reprapfirmware",
            "; start (RepRapFirmware, no heating: clay is cold)\nG21\nG90\nG28\nM83\nM302 P1 ; allow cold extrusion\nG92 E0\n",
            "; end: lift clear of the rim, present the part, motors off\nG90\nG0 Z50.000 F3000\nG0 X0.000 Y190.000 F3000\nM18\n",
        ),
    ] {
        let design = VASE.replace(
            "[shape]",
            &format!("[printer]\ndialect = \"{dialect}\"\n[shape]"),
        );
        let (run, g) = gcode_with(&design, &[]);
        assert!(run.status.success(), "{dialect}: {}", text(&run.stderr));
        assert!(
            g.contains(start),
            "{dialect} start:\n{}",
            &g[g.find("; start").unwrap()..][..300]
        );
        assert!(
            g.contains(end),
            "{dialect} end:\n{}",
            &g[g.rfind("; end:").unwrap()..]
        );
        // Nothing of the templates between the first and the last extruding move.
        let lines: Vec<&str> = g.lines().collect();
        let extruding = |l: &&str| l.starts_with("G1 ") && l.contains(" E");
        let first = lines.iter().position(extruding).unwrap();
        let last = lines.iter().rposition(extruding).unwrap();
        for l in &lines[first..=last] {
            assert!(
                l.starts_with("G1 ")
                    || l.starts_with(";LAYER:")
                    || l.starts_with("M73 ")
                    || l.starts_with("M117 Layer")
                    || l.starts_with("SET_PRINT_STATS_INFO CURRENT_LAYER"),
                "{dialect}: `{l}` inside the path"
            );
        }
    }
    // A delta homes to the top to present the part.
    let (_, g) = gcode_with(VASE, &["--printer", "wasp-2040-clay"]);
    assert!(
        g.contains("G0 Z50.000 F4002\nG28\nM84\n"),
        "{}",
        &g[g.rfind("; end:").unwrap()..]
    );
}

#[test]
fn custom_templates_fill_placeholders_and_unknown_ones_are_named() {
    let design = VASE.replace(
        "[shape]",
        "[printer]\nstart_gcode = \"G28\\nM117 {design_name} {layers} layers {clay_volume_cm3} cm3\\nG0 X{first_x} Y{first_y} Z{first_z}\\n\"\nend_gcode = \"G0 Z{park_z}\\nM84 ; {print_time}\\n\"\n[shape]",
    );
    let (run, g) = gcode_with(&design, &[]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(
        g.contains("M117 test vase 40 layers"),
        "{}",
        &g[..2000.min(g.len())]
    );
    assert!(g.contains("G0 Z50.000\nM84 ; "));
    let bad = VASE.replace(
        "[shape]",
        "[printer]\nstart_gcode = \"G28\\nG0 Z{first_zz}\\n\"\n[shape]",
    );
    let (run, _) = gcode_with(&bad, &[]);
    let err = text(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(
        err.contains("printer.start_gcode") && err.contains("{first_zz}"),
        "{err}"
    );
}

#[test]
fn host_metadata_progress_and_thumbnail_and_each_can_be_left_out() {
    let (run, g) = gcode_with(VASE, &[]);
    assert!(run.status.success());
    for needle in [
        ";FLAVOR:Marlin",
        ";TIME:",
        ";Filament used: ",
        ";LAYER_COUNT:",
        "; estimated printing time (normal mode) = ",
        "; filament used [mm] = ",
        "; filament used [cm3] = ",
        "; total layers count = ",
        "; thumbnail begin 32x32 ",
        "; thumbnail begin 220x220 ",
        ";LAYER:0\n",
        "M117 Layer 1/",
        "M73 P0 R",
        "M73 P50 R",
        "M73 P100 R0",
    ] {
        assert!(g.contains(needle), "{needle} missing");
    }
    let time: f64 = g
        .lines()
        .find_map(|l| l.strip_prefix(";TIME:"))
        .unwrap()
        .parse()
        .unwrap();
    assert!(time > 60.0, "{time}");
    let none = VASE.replace(
        "[shape]",
        "[printer]\nhost_metadata = false\nprogress = false\nthumbnail = false\n[shape]",
    );
    let (run, g) = gcode_with(&none, &[]);
    assert!(run.status.success());
    for gone in [
        ";TIME:",
        "; thumbnail begin",
        "M73 ",
        ";LAYER:",
        "M117 Layer",
    ] {
        assert!(!g.contains(gone), "{gone} still written");
    }
}

#[test]
fn lower_acceleration_gives_a_longer_estimate() {
    let time = |accel: &str| {
        let d = VASE.replace(
            "[shape]",
            &format!("[printer]\nmax_acceleration = {accel}\n[shape]"),
        );
        let (run, g) = gcode_with(&d, &[]);
        assert!(run.status.success(), "{}", text(&run.stderr));
        g.lines()
            .find_map(|l| l.strip_prefix(";TIME:"))
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let (fast, slow) = (time("3000.0"), time("10.0"));
    assert!(slow > fast * 1.05, "{slow} vs {fast}");
}
