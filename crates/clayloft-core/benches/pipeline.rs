//! Speed targets of the core pipeline (issue: design → G-code for a 720-sample × 300-layer design
//! in under 50 ms; G-code writing at 200 MB/s or more). Run with `cargo bench -p clayloft-core`.

use std::hint::black_box;

use clayloft_core::gcode::write_gcode;
use clayloft_core::load::parse_design;
use clayloft_core::pipeline::{PrintJob, Surface};
use clayloft_core::toolpath::{PathPoint, Toolpath};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3};

/// 720 samples per section, 150 mm at 0.5 mm layers = 300 layers, with a belly and a texture.
const BIG_DESIGN: &str = include_str!("../../../assets/benchmarks/vase-720x300.toml");

fn pipeline(c: &mut Criterion) {
    // The heap as `clayloft gcode` sets it up (for every benchmark of this binary after).
    clayloft_core::heap::tune_for_batch_command();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench.gcode");
    let mut g = c.benchmark_group("pipeline");
    g.sample_size(20);
    g.bench_function("design_to_gcode_file_720x300", |b| {
        b.iter(|| {
            let design = parse_design(BIG_DESIGN).unwrap();
            let job = clayloft_core::run(&design).unwrap();
            clayloft_core::atomic::write_atomically(&out, |w| write_gcode(&design, &job, w))
                .unwrap();
            black_box(job.toolpath.points.len())
        })
    });
    // What `clayloft gcode` does in its process: the same, with the self-check of the program
    // on its way to the disk (the body's moves as the writer tells them).
    g.bench_function("design_to_checked_gcode_file_720x300", |b| {
        b.iter(|| {
            let design = parse_design(BIG_DESIGN).unwrap();
            let job = clayloft_core::run(&design).unwrap();
            let written = clayloft_core::export::write_checked_gcode(&design, &job, &out).unwrap();
            black_box(written.summary.points)
        })
    });
    // The same vessel with a two-bead wall (issue 13): the inner bead offset per section, twice
    // the path.
    let two_beads = BIG_DESIGN.replace("[shape]\n", "[shape]\nwalls = 2\n");
    assert!(parse_design(&two_beads).unwrap().shape.walls == 2);
    g.bench_function("design_to_gcode_file_720x300_two_beads", |b| {
        b.iter(|| {
            let design = parse_design(&two_beads).unwrap();
            let job = clayloft_core::run(&design).unwrap();
            clayloft_core::atomic::write_atomically(&out, |w| write_gcode(&design, &job, w))
                .unwrap();
            black_box(job.toolpath.points.len())
        })
    });
    g.finish();
    // Of that, the inner bead alone: 301 sections offset by a line width.
    let design = parse_design(BIG_DESIGN).unwrap();
    let surface = clayloft_core::pipeline::build_surface(&design).unwrap();
    let mut g = c.benchmark_group("walls");
    g.sample_size(10);
    g.bench_function("inner_bead_720x300", |b| {
        b.iter(|| black_box(clayloft_core::walls::inner_beads(&surface, 2, 3.0, None).unwrap()))
    });
    g.finish();
    // The printability verdict (SPEC §14) of the same vessel: 303 layers judged pairwise, and
    // with a soft porcelain that fails, the bisection for the minimum layer time on top.
    let job = clayloft_core::run(&design).unwrap();
    let mut soft = design.clone();
    soft.clay = Some(clayloft_core::clay::ClayTable {
        body: Some("porcelain".into()),
        yield_stress: Some(100.0),
        structuration_rate: Some(0.1),
        ..Default::default()
    });
    assert!(
        clayloft_core::printability::assess(&soft, &job.surface, &job.toolpath)
            .unwrap()
            .min_layer_time_to_stand
            .is_some()
    );
    let mut g = c.benchmark_group("printability");
    g.sample_size(10);
    g.bench_function("assess_720x300", |b| {
        b.iter(|| {
            black_box(
                clayloft_core::printability::assess(&design, &job.surface, &job.toolpath).unwrap(),
            )
        })
    });
    g.bench_function("assess_720x300_with_min_layer_time", |b| {
        b.iter(|| {
            black_box(
                clayloft_core::printability::assess(&soft, &job.surface, &job.toolpath).unwrap(),
            )
        })
    });
    g.bench_function("droops_720x300", |b| {
        b.iter(|| black_box(clayloft_core::printability::droops(&design, &job.surface).unwrap()))
    });
    g.finish();
    // The checker (`clayloft check`): parse, then the layer search (every point against the
    // chords of the layers below); and the self-check `clayloft gcode` runs on its own file
    // before writing it, the layers shown by witnesses.
    let mut text = Vec::new();
    write_gcode(&design, &job, &mut text).unwrap();
    let text = String::from_utf8(text).unwrap();
    let limits = clayloft_core::check::Limits::from(&design.printer);
    assert!(
        clayloft_core::check::check_gcode(&text, &limits)
            .unwrap()
            .violations
            .is_empty()
    );
    let mut g = c.benchmark_group("check");
    g.sample_size(10);
    g.bench_function("check_gcode_720x300", |b| {
        b.iter(|| black_box(clayloft_core::check::check_gcode(&text, &limits).unwrap()))
    });
    g.bench_function("verify_gcode_720x300", |b| {
        b.iter(|| {
            assert!(
                clayloft_core::check::verify_gcode(&text, &limits)
                    .unwrap()
                    .is_none()
            )
        })
    });
    // Of that, reading the file's moves.
    g.bench_function("parse_gcode_720x300", |b| {
        b.iter(|| black_box(clayloft_core::check::parse_moves(&text).unwrap()))
    });
    g.finish();
}

/// Base fill of a 100 mm foot (issue 13): a six-point star 100 mm across (outer radius 50 mm,
/// inner 22 mm) sampled at 720 points, 3 mm beads — rings, bridges and corner spurs.
fn base_fill(c: &mut Criterion) {
    let star: Vec<DVec2> = (0..12)
        .map(|i| {
            DVec2::from_angle(std::f64::consts::TAU * i as f64 / 12.0)
                * if i % 2 == 0 { 50.0 } else { 22.0 }
        })
        .collect();
    let foot = clayloft_core::geometry::resample_closed(&star, 720);
    let circle: Vec<DVec2> = (0..720)
        .map(|i| DVec2::from_angle(std::f64::consts::TAU * i as f64 / 720.0) * 50.0)
        .collect();
    let mut g = c.benchmark_group("base_fill");
    g.sample_size(20);
    g.bench_function("star_100mm", |b| {
        b.iter(|| {
            black_box(
                clayloft_core::base_fill::fill_foot(&foot, 3.0)
                    .unwrap()
                    .path
                    .len(),
            )
        })
    });
    g.bench_function("disc_100mm", |b| {
        b.iter(|| {
            black_box(
                clayloft_core::base_fill::fill_foot(&circle, 3.0)
                    .unwrap()
                    .path
                    .len(),
            )
        })
    });
    g.finish();
}

/// A 1 M-point helix, written to memory: formatting speed, in bytes per second.
fn gcode_writing(c: &mut Criterion) {
    let design = parse_design(BIG_DESIGN).unwrap();
    let n = 1_000_000;
    let points = (0..n)
        .map(|i| {
            let a = i as f64 * 0.01;
            PathPoint {
                pos: DVec3::new(
                    90.0 + 40.0 * a.cos(),
                    95.0 + 40.0 * a.sin(),
                    0.5 + i as f64 * 1e-4,
                ),
                thickness: 0.5,
                flow: 1.0,
                speed: 20.0,
            }
        })
        .collect();
    let job = PrintJob {
        surface: std::sync::Arc::new(Surface {
            sections: Vec::new(),
            layers: 300,
            layer_pitch: 0.5,
            center: DVec2::new(90.0, 95.0),
            findings: Vec::new(),
            metrics: Default::default(),
            point_leans_deg: Vec::new(),
        }),
        beads: std::sync::Arc::default(),
        verdict: None,
        toolpath: std::sync::Arc::new(Toolpath {
            points,
            base_points: 0,
            revolutions: 1,
            layer_starts: vec![0],
            findings: Vec::new(),
        }),
    };
    let mut buf = Vec::with_capacity(64 << 20);
    write_gcode(&design, &job, &mut buf).unwrap();
    let bytes = buf.len() as u64;
    let mut g = c.benchmark_group("gcode");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(bytes));
    g.bench_function("write_1M_points", |b| {
        b.iter(|| {
            buf.clear();
            write_gcode(&design, &job, &mut buf).unwrap();
            black_box(buf.len())
        })
    });
    g.finish();
    // The header's figures of the benchmark vessel: the motion planner (look-ahead, corners,
    // trapezoids over its 220 706 moves), the clay volume and the path length.
    let design = parse_design(BIG_DESIGN).unwrap();
    let job = clayloft_core::run(&design).unwrap();
    let mut g = c.benchmark_group("gcode");
    g.bench_function("summary_720x300", |b| {
        b.iter(|| black_box(clayloft_core::gcode::summarize(&design, &job)))
    });
    g.finish();
}

/// A closed vessel of revolution 300 mm tall with `n` points round and `rings` rings: 2·n·rings
/// triangles, about a million for n = 1000, rings = 501.
fn revolution_mesh(n: usize, rings: usize) -> clayloft_core::stl::Mesh {
    clayloft_core::mesh::revolution(n, rings, 300.0, |z| {
        60.0 + 15.0 * (std::f64::consts::PI * z / 300.0).sin()
    })
}

/// Slicing a million-triangle vessel into 300 layers (issue 16), and checking it is one closed
/// body first.
fn mesh_slicing(c: &mut Criterion) {
    use clayloft_core::mesh::{check_closed_body, layer_heights, slice_outlines};
    let mesh = revolution_mesh(1000, 501);
    let (heights, _) = layer_heights(300.0, 1.0);
    let mut g = c.benchmark_group("mesh");
    g.sample_size(10);
    g.bench_function("check_1M_triangles", |b| {
        b.iter(|| black_box(check_closed_body(&mesh).unwrap().triangles.len()))
    });
    g.bench_function("slice_1M_triangles_300_layers", |b| {
        b.iter(|| black_box(slice_outlines(&mesh, &heights).unwrap().len()))
    });
    g.finish();
}

criterion_group!(benches, pipeline, base_fill, gcode_writing, mesh_slicing);
criterion_main!(benches);
