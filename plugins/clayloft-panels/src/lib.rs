//! The panels (SPEC §8): a file bar, the design's parameters on the left (every field of the
//! design file, with units and a short explanation), findings and the nozzle replay on the right,
//! and a status line. Panels edit the design document only; everything else follows from it.

mod design_form;
mod figures;
mod reference;
mod source_preview;
mod widgets;

use std::path::PathBuf;

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use clayloft_core::gcode::format_duration;
use clayloft_edit::{DragHint, HistoryCommand, PanelInUse, Selection};
use clayloft_files::{FileCommand, FileStatus};
use clayloft_model::*;
use clayloft_replay::{Replay, ReplayPath};
use clayloft_view::{FrameVessel, ViewSettings, WallStats};

/// How long a pick or drag hint stays in the status line.
const HINT_LIFETIME: std::time::Duration = std::time::Duration::from_secs(12);

/// Paths typed in the file bar.
#[derive(Resource, Debug, Clone, Default)]
pub struct FileFields {
    pub design: String,
    pub gcode: String,
    pub stl: String,
    /// The document path the fields were filled from.
    filled_from: Option<Option<PathBuf>>,
}

pub struct PanelsPlugin;

impl Plugin for PanelsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<FileFields>()
            .add_systems(
                EguiPrimaryContextPass,
                draw_panels.in_set(clayloft_ui::UiSystems::Panels),
            )
            .add_systems(
                EguiPrimaryContextPass,
                (draw_source_previews, draw_reference).in_set(clayloft_ui::UiSystems::Windows),
            );
    }
}

fn draw_panels(
    mut contexts: EguiContexts,
    doc: Option<ResMut<DesignDoc>>,
    status: Res<ModelStatus>,
    file_status: Res<FileStatus>,
    mut fields: ResMut<FileFields>,
    mut files: MessageWriter<FileCommand>,
    mut history_cmd: MessageWriter<HistoryCommand>,
    history: Res<clayloft_edit::History>,
    mut settings: ResMut<ViewSettings>,
    (mut replay, replay_path): (ResMut<Replay>, Res<ReplayPath>),
    (wall, engine, mut redraw): (
        Res<WallStats>,
        Res<Engine>,
        MessageWriter<bevy::window::RequestRedraw>,
    ),
    vessel: Query<&VesselSurface>,
    toolpath: Query<(&ToolpathPath, Option<&ToolpathPrintability>)>,
    selection: Res<Selection>,
    (mut panel, mut frame): (ResMut<PanelInUse>, MessageWriter<FrameVessel>),
    (mut job_work, hint, mut hint_since): (
        Local<figures::JobWork>,
        Res<DragHint>,
        Local<Option<std::time::Instant>>,
    ),
) -> Result {
    if hint.is_changed() {
        *hint_since = Some(std::time::Instant::now());
    }
    let ctx = contexts.ctx_mut()?.clone();
    let Some(doc_now) = doc.as_deref() else {
        return Ok(());
    };
    // The job's figures and the self-check of its program, each on a thread of its own once
    // per toolpath; the check once the toolpath has settled (not while a handle is dragged).
    let now = std::time::Instant::now();
    let shown = toolpath.iter().next().map(|(tp, _)| {
        let key = figures::JobKey::new(&tp.0, &doc_now.design);
        job_work.update(key, now, |design| engine.current_job(design).ok())
    });
    if shown.as_ref().is_some_and(|s| s.busy) {
        redraw.write(bevy::window::RequestRedraw);
    }
    let Some(mut doc) = doc else { return Ok(()) };
    if fields.filled_from.as_ref() != Some(&doc.path) {
        fields.filled_from = Some(doc.path.clone());
        let base = doc
            .path
            .clone()
            .unwrap_or_else(|| PathBuf::from("untitled.toml"));
        // A mesh opened on its own is saved as a design next to it, never over it.
        let design_file = if clayloft_core::load::is_mesh_file(&base) {
            base.with_extension("toml")
        } else {
            base.clone()
        };
        fields.design = design_file.display().to_string();
        fields.gcode = base.with_extension("gcode").display().to_string();
        fields.stl = base.with_extension("stl").display().to_string();
    }
    let mut root = egui::Ui::new(
        ctx.clone(),
        "root".into(),
        egui::UiBuilder::new()
            .layer_id(egui::LayerId::background())
            .max_rect(ctx.viewport_rect()),
    );
    let mut design = doc.design.clone();

    egui::Panel::top("file bar").show(&mut root, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label("Design");
            ui.add(egui::TextEdit::singleline(&mut fields.design).desired_width(260.0));
            if ui
                .button("Open")
                .on_hover_text("Open this design file (TOML, SPEC §6)")
                .clicked()
            {
                files.write(FileCommand::Open(PathBuf::from(&fields.design)));
            }
            if ui
                .button("Save")
                .on_hover_text("Save the design to this path; it loads back identical")
                .clicked()
            {
                files.write(FileCommand::Save(Some(PathBuf::from(&fields.design))));
            }
            ui.separator();
            ui.add(egui::TextEdit::singleline(&mut fields.gcode).desired_width(180.0));
            if ui
                .button("Export G-code")
                .on_hover_text("The single spiral path, as `clayloft gcode` writes it")
                .clicked()
            {
                files.write(FileCommand::ExportGcode(PathBuf::from(&fields.gcode)));
            }
            ui.add(egui::TextEdit::singleline(&mut fields.stl).desired_width(160.0));
            if ui
                .button("Export STL")
                .on_hover_text("The printed wall as a closed mesh")
                .clicked()
            {
                files.write(FileCommand::ExportStl(PathBuf::from(&fields.stl)));
            }
            ui.separator();
            if ui
                .add_enabled(history.can_undo(), egui::Button::new("⟲ Undo"))
                .on_hover_text("Ctrl+Z")
                .clicked()
            {
                history_cmd.write(HistoryCommand::Undo);
            }
            if ui
                .add_enabled(history.can_redo(), egui::Button::new("⟳ Redo"))
                .on_hover_text("Ctrl+Shift+Z")
                .clicked()
            {
                history_cmd.write(HistoryCommand::Redo);
            }
            ui.separator();
            // Edited on a copy and written back only when a box changed: a `ResMut` touched
            // every frame would tell the view to rebuild every frame.
            let mut shown = *settings;
            ui.checkbox(&mut shown.show_wall, "wall");
            ui.checkbox(&mut shown.show_toolpath, "toolpath");
            ui.checkbox(&mut shown.show_control_lines, "control lines");
            ui.checkbox(&mut shown.show_build_volume, "build volume");
            ui.checkbox(&mut shown.colour_by_safety, "safety colours")
                .on_hover_text("Colour the wall by whether it stands while printing (red: it fails) instead of by its lean");
            settings.set_if_neq(shown);
            if ui
                .button("Frame vessel")
                .on_hover_text("Point the camera at the whole vessel (F)")
                .clicked()
            {
                frame.write(FrameVessel);
            }
        });
    });

    egui::Panel::bottom("status line").show(&mut root, |ui| {
        ui.horizontal_wrapped(|ui| {
            if let (Some(s), Some((tp, _))) = (vessel.iter().next(), toolpath.iter().next()) {
                let figures = shown.as_ref().and_then(|s| s.figures);
                let (length, time) = figures.map_or(("…".into(), "…".into()), |(l, t)| {
                    (format!("{:.1} m", l / 1000.0), format_duration(t))
                });
                ui.label(format!(
                    "{} layers · {} points · path {length} · print ≈ {time} · max overhang {:.1}°",
                    s.0.layers,
                    tp.0.points.len(),
                    s.0.metrics.max_overhang_deg,
                ));
                if wall.violating_points > 0 {
                    ui.colored_label(
                        egui::Color32::from_rgb(240, 60, 60),
                        format!(
                            "{} points past the overhang limit (red)",
                            wall.violating_points
                        ),
                    );
                }
            }
            if status.is_stale() {
                ui.colored_label(
                    egui::Color32::from_rgb(240, 200, 90),
                    "showing the last design that could be built (faded) — to fix:",
                );
            }
            for e in &status.errors {
                ui.colored_label(egui::Color32::from_rgb(255, 90, 90), format!("error: {e}"));
            }
            let now = std::time::Instant::now();
            if let Some(h) = &hint.0
                && hint_since.is_some_and(|t| now.duration_since(t) < HINT_LIFETIME)
            {
                ui.label(h);
            }
            if let Some(m) = file_status.current(now) {
                let c = if file_status.is_error {
                    egui::Color32::from_rgb(255, 90, 90)
                } else {
                    egui::Color32::from_rgb(150, 220, 150)
                };
                ui.colored_label(c, m);
            }
        });
    });

    egui::Panel::left("design")
        .resizable(true)
        .default_size(330.0)
        .show(&mut root, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                design_form::design_form(ui, &mut design, selection.0, &status);
            });
        });

    egui::Panel::right("checks")
        .resizable(true)
        .default_size(300.0)
        .show(&mut root, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                let mut edited = replay.clone();
                let planned = shown.as_ref().and_then(|s| s.figures).map(|(_, t)| t);
                replay_panel(ui, &mut edited, &replay_path, planned);
                replay.set_if_neq(edited);
                ui.separator();
                let (path, verdict) = toolpath.iter().next().unzip();
                findings_panel(ui, vessel.iter().next(), path, &design, &status);
                if design.constraints.enforce && !status.is_stale() {
                    program_panel(ui, shown.as_ref().and_then(|s| s.check.as_ref()));
                }
                if let Some(p) = verdict.flatten() {
                    ui.separator();
                    printability_panel(ui, &p.0, &design, &status);
                }
            });
        });

    // What is left between the panels is the 3D view: the tool windows stay inside it.
    clayloft_ui::set_tool_area(&ctx, root.available_rect_before_wrap());
    if design != doc.design {
        doc.design = design;
    }
    panel.set_if_neq(PanelInUse {
        hovered: ctx.egui_wants_pointer_input() || ctx.is_pointer_over_egui(),
        editing: ctx.egui_is_using_pointer(),
        typing: ctx.egui_wants_keyboard_input(),
    });
    Ok(())
}

/// The title of the window with the paper's tables.
const REFERENCE_WINDOW: &str = "Reference: the paper's tables";

/// The paper's reference tables, for teaching ([`reference`]).
fn draw_reference(mut contexts: EguiContexts) -> Result {
    let ctx = contexts.ctx_mut()?.clone();
    clayloft_ui::tool_window(
        &ctx,
        REFERENCE_WINDOW,
        clayloft_ui::Corner::BottomCentre,
        false,
    )
    .default_width(620.0)
    .show(&ctx, |ui| {
        egui::ScrollArea::vertical()
            .max_height(420.0)
            .show(ui, reference::reference);
    });
    clayloft_ui::toggle_on_title_click(&ctx, REFERENCE_WINDOW, false);
    Ok(())
}

/// The image / SVG source windows of the contours.
fn draw_source_previews(
    mut contexts: EguiContexts,
    doc: Option<Res<DesignDoc>>,
    mut previews: Local<[source_preview::SourcePreview; 2]>,
) -> Result {
    let ctx = contexts.ctx_mut()?.clone();
    if let Some(doc) = doc {
        source_preview::source_windows(&ctx, &doc.design, &mut previews);
    }
    Ok(())
}

/// The replay's controls. The replay plays at the path's own speeds; its clock is shown in the
/// printer's time, `planned_s` (the motion planner's estimate, the status line's) over the
/// path's time at those speeds, so that its end reads what the status line and the G-code say.
fn replay_panel(ui: &mut egui::Ui, replay: &mut Replay, path: &ReplayPath, planned_s: Option<f64>) {
    ui.heading("Nozzle replay");
    ui.label(
        egui::RichText::new(
            "Watch the nozzle lay the spiral. The holder above the tube must never touch what is already printed; the wall must never lean past the overhang limit.",
        )
        .small()
        .weak(),
    );
    let total = path.timeline.total_s();
    ui.horizontal(|ui| {
        if ui.toggle_value(&mut replay.active, "show").changed() && !replay.active {
            replay.playing = false;
        }
        let label = if replay.playing {
            "⏸ pause"
        } else {
            "⏵ play"
        };
        if ui.button(label).clicked() {
            replay.active = true;
            if !replay.playing && replay.time_s >= total {
                replay.time_s = 0.0;
            }
            replay.playing = !replay.playing;
        }
        if ui.button("⏮").on_hover_text("back to the start").clicked() {
            replay.time_s = 0.0;
        }
    });
    let mut t = replay.time_s;
    let clock = planned_s
        .map(|p| p / total)
        .filter(|k| k.is_finite() && *k > 0.0)
        .unwrap_or(1.0);
    let label = format!(
        "{} / {}",
        format_duration(t * clock),
        format_duration(total * clock)
    );
    let scrub = ui.add(
        egui::Slider::new(&mut t, 0.0..=total.max(1e-3))
            .show_value(false)
            .text(label),
    );
    if scrub.changed() {
        replay.active = true;
        replay.time_s = t;
    }
    ui.add(
        egui::Slider::new(&mut replay.speed, 1.0..=2000.0)
            .logarithmic(true)
            .suffix("×")
            .text("speed"),
    );
    let passed = path.passed_events();
    if let Some(e) = path.flag_now() {
        ui.colored_label(
            egui::Color32::from_rgb(255, 80, 80),
            format!("{} at point {} ({:.1})", e.what, e.line, e.value),
        );
    }
    if path.checking {
        ui.label(if replay.active {
            "checking the path for collisions, overhangs and loops …"
        } else {
            "the path is checked for collisions, overhangs and loops when the replay is shown"
        });
    } else if path.events.is_empty() {
        ui.colored_label(
            egui::Color32::from_rgb(150, 220, 150),
            "no collision, overhang, unsupported point or loop on this path",
        );
    } else {
        ui.label(format!(
            "{} of {} flagged points passed",
            passed.len(),
            path.events.len()
        ));
        egui::ScrollArea::vertical()
            .id_salt("events")
            .max_height(140.0)
            .show(ui, |ui| {
                for e in passed.iter().rev().take(200) {
                    ui.label(format!("point {}: {} ({:.1})", e.line, e.what, e.value));
                }
            });
    }
}

/// The self-check's verdict on the job's G-code (what "Export G-code" and "Print design" run):
/// `None` while it is worked out.
fn program_panel(ui: &mut egui::Ui, verdict: Option<&figures::ProgramVerdict>) {
    match verdict {
        Some(Ok(())) => {
            ui.colored_label(
                egui::Color32::from_rgb(150, 220, 150),
                "its G-code passes the checker on this printer",
            );
        }
        Some(Err(why)) => {
            ui.colored_label(
                egui::Color32::from_rgb(255, 90, 90),
                format!("its G-code does not pass the checker: the design {why}. Export G-code and Print design refuse it."),
            );
        }
        None => {
            ui.label(egui::RichText::new("checking its G-code …").weak());
        }
    }
}

fn findings_panel(
    ui: &mut egui::Ui,
    surface: Option<&VesselSurface>,
    path: Option<&ToolpathPath>,
    design: &clayloft_core::Design,
    status: &ModelStatus,
) {
    ui.heading("Constraints");
    ui.label(
        egui::RichText::new(format!(
            "Clay cannot bridge or be supported: every layer must rest on the one below, leaning at most {}° (wall colour: clay = upright, amber = near the limit, red = past it).",
            design.printer.max_overhang_deg
        ))
        .small()
        .weak(),
    );
    if status.is_stale() {
        // Nothing is claimed about a design that could not be built.
        ui.colored_label(
            egui::Color32::from_rgb(240, 200, 90),
            "not checked: the design has an error (see the status line). What follows is about the last design that could be built.",
        );
    }
    let Some(s) = surface else { return };
    let path_findings = path.map(|p| p.0.findings.as_slice()).unwrap_or_default();
    if s.0.findings.is_empty() && path_findings.is_empty() && !status.is_stale() {
        ui.colored_label(
            egui::Color32::from_rgb(150, 220, 150),
            "the design keeps every limit as drawn",
        );
    }
    for f in s.0.findings.iter().chain(path_findings) {
        let color = if f.corrected {
            egui::Color32::from_rgb(240, 200, 90)
        } else {
            egui::Color32::from_rgb(255, 90, 90)
        };
        ui.colored_label(color, f.to_string());
    }
}

/// Will the wet wall stand while it is printed: the core's verdict in words (SPEC §14).
fn printability_panel(
    ui: &mut egui::Ui,
    p: &clayloft_core::printability::Printability,
    design: &clayloft_core::Design,
    status: &ModelStatus,
) {
    ui.heading("Will it stand?");
    ui.label(
        egui::RichText::new(format!(
            "Wet {} is soft: the layers low in the wall carry all the clay above them while they are still stiffening. A safety factor above 1 means they hold (tick \"safety colours\" to see it on the wall: red fails, amber is close).",
            p.body.name
        ))
        .small()
        .weak(),
    );
    if status.is_stale() {
        return;
    }
    let color = if p.factor >= 1.5 {
        egui::Color32::from_rgb(150, 220, 150)
    } else if p.factor >= 1.0 {
        egui::Color32::from_rgb(240, 200, 90)
    } else {
        egui::Color32::from_rgb(255, 90, 90)
    };
    ui.colored_label(
        color,
        format!(
            "safety factor {:.2} against {} at layer {} (z {:.1} mm), when layer {} is laid",
            p.factor,
            p.mechanism.name(),
            p.layer,
            p.z,
            p.loaded_by
        ),
    );
    match p.warning(design) {
        Some(w) => {
            ui.colored_label(egui::Color32::from_rgb(255, 90, 90), w);
        }
        None => {
            ui.label(format!(
                "It stands. Were it to fail, it would be by {}: {}.",
                p.mechanism.name(),
                p.mechanism.explanation()
            ));
        }
    }
    // Stretches of bead with nothing under them, the worst first (what `clayloft gcode` prints).
    for d in p.droops.iter().take(3) {
        ui.colored_label(
            egui::Color32::from_rgb(240, 200, 90),
            d.summary(p.body.name),
        );
    }
    if p.droops.len() > 3 {
        ui.label(format!("droop: {} more layers", p.droops.len() - 3));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    /// The constraint panel of a design that keeps every limit, with and without an error in
    /// the edit that followed it.
    fn panel(status: ModelStatus) -> Harness<'static> {
        let design = clayloft_core::load::parse_design(
            "version = 1\n[shape]\nheight = 60.0\nlower = { type = \"circle\", radius = 40.0 }\nupper = { type = \"circle\", radius = 45.0 }\n",
        )
        .unwrap();
        let job = clayloft_core::run(&design).unwrap();
        let (surface, path) = (VesselSurface(job.surface), ToolpathPath(job.toolpath));
        Harness::builder()
            .with_size(egui::vec2(320.0, 600.0))
            .build_ui(move |ui| findings_panel(ui, Some(&surface), Some(&path), &design, &status))
    }

    /// The verdict in words: a vessel that stands, and a tall soft one that does not (with what
    /// would help).
    #[test]
    fn the_printability_panel_says_whether_the_wall_stands_and_why() {
        let verdict = |printer: &str, extra: &str, height: f64| {
            let design = clayloft_core::load::parse_design(&format!(
                "version = 1\n[printer]\nmax_z = 1000.0\n{printer}[shape]\nheight = {height}\nlower = {{ type = \"circle\", radius = 60.0 }}\nupper = {{ type = \"circle\", radius = 60.0 }}\n{extra}"
            ))
            .unwrap();
            let job = clayloft_core::run(&design).unwrap();
            let p =
                clayloft_core::printability::assess(&design, &job.surface, &job.toolpath).unwrap();
            let mut h = Harness::builder()
                .with_size(egui::vec2(320.0, 600.0))
                .build_ui(move |ui| printability_panel(ui, &p, &design, &ModelStatus::default()));
            h.run();
            h
        };
        let h = verdict("", "", 60.0);
        assert!(h.query_by_label_contains("is laid").is_some());
        assert!(h.query_by_label_contains("It stands.").is_some());
        let h = verdict(
            "",
            "[clay]\nbody = \"porcelain\"\nstructuration_rate = 0.05\n",
            400.0,
        );
        assert!(
            h.query_by_label_contains("warning: the wall will not stand")
                .is_some()
        );
        assert!(h.query_by_label_contains("min_layer_time").is_some());
        assert!(h.query_by_label_contains("droop").is_none());
        // A deep, steep texture printed without enforcement on a printer that allows 70°:
        // stretches of bead with nothing under them, named under the verdict.
        let h = verdict(
            "max_overhang_deg = 70.0\n",
            "[texture]\ncombine = \"sum\"\nphase_drift = 40.0\n[texture.x]\nwave = \"square\"\nperiod = 90\namplitude = 4.0\n[constraints]\nenforce = false\n",
            30.0,
        );
        let named = h.query_all_by_label_contains("droop: layer").count();
        assert!((1..=3).contains(&named), "{named} droops named");
    }

    /// The replay's clock reads the printer's time: its end is the planned time the status
    /// line and the G-code give, not the time at the path's own speeds.
    #[test]
    fn the_replay_clock_ends_at_the_planned_time() {
        let design = clayloft_core::load::parse_design(
            "version = 1\n[shape]\nheight = 20.0\nsamples = 90\nlower = { type = \"rose\", radius = 40.0, amplitude = 6.0, petals = 5 }\nupper = { type = \"circle\", radius = 35.0 }\n",
        )
        .unwrap();
        let job = clayloft_core::run(&design).unwrap();
        let planned = clayloft_core::gcode::summarize(&design, &job).estimated_time_s;
        let path = ReplayPath::unchecked(&job.toolpath);
        let nominal = path.timeline.total_s();
        assert_ne!(format_duration(nominal), format_duration(planned));
        let end = format!("0m 00s / {}", format_duration(planned));
        let mut h = Harness::builder()
            .with_size(egui::vec2(320.0, 300.0))
            .build_ui(move |ui| {
                replay_panel(ui, &mut Replay::default(), &path, Some(planned));
            });
        h.run();
        assert!(h.query_by_label_contains(&end).is_some(), "{end}");
    }

    /// The program check's verdict in words: passing, refused (with why, and that the export
    /// and the printer refuse it), and while it is worked out.
    #[test]
    fn the_program_panel_says_whether_the_g_code_passes() {
        let shown = |verdict: Option<figures::ProgramVerdict>| {
            let mut h = Harness::builder()
                .with_size(egui::vec2(320.0, 300.0))
                .build_ui(move |ui| program_panel(ui, verdict.as_ref()));
            h.run();
            h
        };
        assert!(
            shown(Some(Ok(())))
                .query_by_label_contains("passes the checker")
                .is_some()
        );
        let refused = shown(Some(Err(
            "does not print on this printer (x): overhang".into()
        )));
        assert!(
            refused
                .query_by_label_contains("does not pass the checker: the design does not print on this printer (x): overhang. Export G-code and Print design refuse it")
                .is_some()
        );
        assert!(
            shown(None)
                .query_by_label_contains("checking its G-code")
                .is_some()
        );
    }

    #[test]
    fn the_constraint_panel_claims_nothing_about_an_edit_it_could_not_build() {
        let mut h = panel(ModelStatus::default());
        h.run();
        assert!(
            h.query_by_label("the design keeps every limit as drawn")
                .is_some()
        );
        let mut h = panel(ModelStatus {
            errors: vec![clayloft_core::validate::FieldError::new(
                "texture.x.amplitude",
                "50 mm is outside …",
            )],
        });
        h.run();
        assert!(
            h.query_by_label("the design keeps every limit as drawn")
                .is_none()
        );
        assert!(
            h.query_by_label_contains("not checked: the design has an error")
                .is_some()
        );
    }
}
