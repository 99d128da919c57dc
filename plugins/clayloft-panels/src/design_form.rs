//! Every field of the design file (SPEC §6) as a form, grouped like the file.

use bevy_egui::egui;
use clayloft_core::Design;
use clayloft_core::design::{
    Combine, ContourSpec, ExtrusionMode, HorizontalLine, Texture, VerticalLine, Wave, WaveKind,
};
use clayloft_model::handles::{HandleRole, describe, freedom};

use crate::widgets::{count, explain, field, field_as_at, number, point_list, set_field_problems};
use clayloft_model::ModelStatus;

pub fn design_form(
    ui: &mut egui::Ui,
    d: &mut Design,
    selected: Option<HandleRole>,
    status: &ModelStatus,
) {
    set_field_problems(
        ui,
        status
            .errors
            .iter()
            .map(|e| (e.field.clone(), e.message.clone()))
            .collect(),
    );
    ui.horizontal(|ui| {
        ui.label("Name");
        ui.text_edit_singleline(&mut d.name);
    });
    if let Some(role) = selected {
        explain(
            ui,
            &format!(
                "selected: {} — moves {}. Drag it, or drag a gizmo arrow to move along one direction.",
                describe(role, d),
                freedom(role, d).moves
            ),
        );
    }
    egui::CollapsingHeader::new("Shape")
        .default_open(true)
        .show(ui, |ui| shape(ui, d));
    if let Some(mesh) = &mut d.shape.mesh {
        egui::CollapsingHeader::new("Mesh")
            .default_open(true)
            .show(ui, |ui| {
                explain(
                    ui,
                    "The vessel's shape comes from this mesh, sliced at every layer: the printed wall's outside lies on the mesh's surface.",
                );
                ui.label(format!("file: {}", mesh.path.display()));
                number(
                    ui,
                    "Scale",
                    &mut mesh.scale,
                    "×",
                    0.0001..=10_000.0,
                    "Multiplies the mesh's numbers: 1 if they are millimetres, 10 for centimetres, 25.4 for inches.",
                );
                number(
                    ui,
                    "Turn about x",
                    &mut mesh.rotate_x,
                    "°",
                    -360.0..=360.0,
                    "Turns the mesh before slicing: 90 stands up a mesh exported with y up.",
                );
            });
    } else {
        egui::CollapsingHeader::new("Lower contour (on the bed)")
            .default_open(true)
            .show(ui, |ui| {
                explain(ui, "The closed curve the vessel stands on.");
                contour(ui, "lower", &mut d.shape.lower);
            });
        egui::CollapsingHeader::new("Upper contour (the rim)")
            .default_open(true)
            .show(ui, |ui| {
                explain(
                    ui,
                    "The closed curve at the top; the wall is lofted between the two.",
                );
                contour(ui, "upper", &mut d.shape.upper);
            });
        egui::CollapsingHeader::new("Control lines")
            .default_open(false)
            .show(ui, |ui| control(ui, d));
    }
    egui::CollapsingHeader::new("Texture")
        .default_open(false)
        .show(ui, |ui| texture(ui, &mut d.texture));
    egui::CollapsingHeader::new("Printer")
        .default_open(false)
        .show(ui, |ui| printer(ui, d));
    egui::CollapsingHeader::new("Constraints").default_open(true).show(ui, |ui| {
        ui.checkbox(&mut d.constraints.enforce, "enforce limits")
            .on_hover_text("On: the shape is corrected locally so it prints. Off: violations are only reported.");
        explain(
            ui,
            "Clay has no supports: every point may lean at most the overhang angle from the layer below, the nozzle holder must clear the printed part, and the path must be one continuous spiral.",
        );
    });
}

fn shape(ui: &mut egui::Ui, d: &mut Design) {
    let s = &mut d.shape;
    if s.mesh.is_none() {
        // A mesh's height is the mesh's.
        field(ui, "shape.height", &mut s.height);
    }
    count(
        ui,
        "shape.samples",
        "Samples",
        &mut s.samples,
        3..=20_000,
        "Points per section around the vessel: more follow curves more finely.",
    );
    count(
        ui,
        "shape.base_layers",
        "Base layers",
        &mut s.base_layers,
        0..=20,
        "Solid spiral layers that close the bottom (0 = open cylinder).",
    );
    count(
        ui,
        "shape.walls",
        "Wall beads",
        &mut s.walls,
        1..=clayloft_core::walls::MAX_WALLS,
        "Beads side by side in the wall, inward of the designed outside: 2 or 3 make a thicker, stronger wall, still one continuous spiral.",
    );
    if s.walls > 1 {
        ui.checkbox(&mut s.wall_ties, "tie the beads")
            .on_hover_text("The inner beads zig-zag half a bead outward and back, pressing into the bead outside them every few centimetres.");
    }
    let mut custom = s.center.is_some();
    if ui
        .checkbox(&mut custom, "Place off-centre")
        .on_hover_text("By default the vessel stands at the bed centre.")
        .changed()
    {
        // In the printer's own coordinates: the bed centre.
        let [ox, oy] = d.printer.origin_offset();
        s.center = custom.then(|| [d.printer.bed_x / 2.0 - ox, d.printer.bed_y / 2.0 - oy]);
    }
    if let Some(c) = &mut s.center {
        number(
            ui,
            "Centre x",
            &mut c[0],
            "mm",
            0.0..=10_000.0,
            "Where the vessel's centre sits on the bed.",
        );
        number(
            ui,
            "Centre y",
            &mut c[1],
            "mm",
            0.0..=10_000.0,
            "Where the vessel's centre sits on the bed.",
        );
    }
}

fn contour_kind(spec: &ContourSpec) -> &'static str {
    match spec {
        ContourSpec::Circle { .. } => "circle",
        ContourSpec::Ellipse { .. } => "ellipse",
        ContourSpec::Polygon { .. } => "polygon",
        ContourSpec::Star { .. } => "star",
        ContourSpec::Rose { .. } => "rose",
        ContourSpec::Spline { .. } => "spline",
        ContourSpec::Image { .. } => "image",
        ContourSpec::Svg { .. } => "svg",
    }
}

fn file_field(ui: &mut egui::Ui, path: &mut String, help: &str) {
    ui.horizontal(|ui| {
        ui.label("File").on_hover_text(help);
        ui.text_edit_singleline(path).on_hover_text(help);
    });
}

fn contour(ui: &mut egui::Ui, id: &str, spec: &mut ContourSpec) {
    let kind = contour_kind(spec);
    egui::ComboBox::from_id_salt(format!("{id} kind"))
        .selected_text(kind)
        .show_ui(ui, |ui| {
            let r = 40.0;
            let choices = [
                ("circle", ContourSpec::Circle { radius: r }),
                (
                    "ellipse",
                    ContourSpec::Ellipse {
                        rx: r,
                        ry: r * 0.75,
                    },
                ),
                (
                    "polygon",
                    ContourSpec::Polygon {
                        sides: 6,
                        radius: r,
                        corner_radius: 5.0,
                    },
                ),
                (
                    "star",
                    ContourSpec::Star {
                        points: 5,
                        outer_radius: r,
                        inner_radius: r * 0.75,
                    },
                ),
                (
                    "rose",
                    ContourSpec::Rose {
                        radius: r,
                        amplitude: 4.0,
                        petals: 6,
                    },
                ),
                (
                    "spline",
                    ContourSpec::Spline {
                        points: vec![[r, 0.0], [0.0, r], [-r, 0.0], [0.0, -r]],
                    },
                ),
                (
                    "image",
                    ContourSpec::Image {
                        path: "outline.png".into(),
                        size: 2.0 * r,
                        threshold: None,
                    },
                ),
                (
                    "svg",
                    ContourSpec::Svg {
                        path: "outline.svg".into(),
                        size: 2.0 * r,
                        id: None,
                    },
                ),
            ];
            for (name, value) in choices {
                if ui.selectable_label(kind == name, name).clicked() && kind != name {
                    *spec = value;
                }
            }
        });
    match spec {
        ContourSpec::Circle { radius } => field_as_at(
            ui,
            "contour.radius",
            &format!("shape.{id}.radius"),
            radius,
            None,
        ),
        ContourSpec::Ellipse { rx, ry } => {
            field_as_at(ui, "contour.rx", &format!("shape.{id}.rx"), rx, None);
            field_as_at(ui, "contour.ry", &format!("shape.{id}.ry"), ry, None);
        }
        ContourSpec::Polygon {
            sides,
            radius,
            corner_radius,
        } => {
            count(
                ui,
                &format!("shape.{id}.sides"),
                "Sides",
                sides,
                3..=64,
                "Number of straight sides.",
            );
            field_as_at(
                ui,
                "contour.radius",
                &format!("shape.{id}.radius"),
                radius,
                None,
            );
            number(
                ui,
                "Corner radius",
                corner_radius,
                "mm",
                0.0..=500.0,
                "Rounds the corners; sharp corners make the nozzle jerk.",
            );
        }
        ContourSpec::Star {
            points,
            outer_radius,
            inner_radius,
        } => {
            count(
                ui,
                &format!("shape.{id}.points"),
                "Points",
                points,
                2..=64,
                "Number of tips.",
            );
            field_as_at(
                ui,
                "contour.outer_radius",
                &format!("shape.{id}.outer_radius"),
                outer_radius,
                None,
            );
            field_as_at(
                ui,
                "contour.inner_radius",
                &format!("shape.{id}.inner_radius"),
                inner_radius,
                None,
            );
        }
        ContourSpec::Rose {
            radius,
            amplitude,
            petals,
        } => {
            field_as_at(
                ui,
                "contour.radius",
                &format!("shape.{id}.radius"),
                radius,
                None,
            );
            number(
                ui,
                "Amplitude",
                amplitude,
                "mm",
                0.0..=500.0,
                "How far the petals reach out and in.",
            );
            count(
                ui,
                &format!("shape.{id}.petals"),
                "Petals",
                petals,
                1..=64,
                "Number of petals k.",
            );
        }
        ContourSpec::Spline { points } => {
            explain(
                ui,
                "A smooth closed curve through these points (centripetal Catmull–Rom), in mm around the centre.",
            );
            point_list(
                ui,
                &format!("{id} spline"),
                points,
                ["x", "y"],
                [" mm", " mm"],
                3,
            );
        }
        ContourSpec::Image {
            path,
            size,
            threshold,
        } => {
            file_field(
                ui,
                path,
                "Picture (PNG, JPEG, …), relative to the design file. The largest shape's outline is traced.",
            );
            number(
                ui,
                "Size",
                size,
                "mm",
                1.0..=1000.0,
                "Length of the outline's longer side.",
            );
            let mut manual = threshold.is_some();
            if ui
                .checkbox(&mut manual, "manual threshold")
                .on_hover_text("Off: Otsu's method picks the grey level that best separates shape and background.")
                .changed()
            {
                *threshold = manual.then_some(128);
            }
            if let Some(t) = threshold {
                ui.add(egui::Slider::new(t, 0..=255).text("grey level"))
                    .on_hover_text(
                        "Pixels on the shape's side of this grey level belong to the shape.",
                    );
            }
        }
        ContourSpec::Svg { path, size, id } => {
            file_field(
                ui,
                path,
                "SVG drawing, relative to the design file. Its first closed path is used.",
            );
            number(
                ui,
                "Size",
                size,
                "mm",
                1.0..=1000.0,
                "Length of the outline's longer side.",
            );
            let mut text = id.clone().unwrap_or_default();
            ui.horizontal(|ui| {
                ui.label("Path id")
                    .on_hover_text("Use the path with this id instead of the first closed one.");
                if ui.text_edit_singleline(&mut text).changed() {
                    *id = (!text.trim().is_empty()).then(|| text.trim().to_string());
                }
            });
        }
    }
}

fn control(ui: &mut egui::Ui, d: &mut Design) {
    explain(
        ui,
        "Vertical lines push the wall out (or in) along its height; horizontal lines raise or lower a section around the vessel.",
    );
    let new_vertical = || VerticalLine {
        points: vec![[0.0, 0.0], [0.5, 5.0], [1.0, 0.0]],
        angle: None,
        width: None,
    };
    removable_groups(
        ui,
        &mut d.control.vertical,
        "Vertical line",
        "+ vertical line",
        new_vertical,
        |ui, l, v| {
            let mut local = v.angle.is_some();
            if ui
                .checkbox(&mut local, "local")
                .on_hover_text("Act only around one angle, with a smooth fall-off.")
                .changed()
            {
                v.angle = local.then_some(0.0);
                v.width = local.then_some(60.0);
            }
            if let Some(a) = &mut v.angle {
                number(
                    ui,
                    "Angle",
                    a,
                    "°",
                    -360.0..=360.0,
                    "Where around the vessel it acts, counter-clockwise from +x.",
                );
            }
            if let Some(w) = &mut v.width {
                number(
                    ui,
                    "Width",
                    w,
                    "°",
                    1.0..=360.0,
                    "How wide around the vessel it acts.",
                );
            }
            explain(
                ui,
                "Points: height fraction t (0 = bed, 1 = rim) and outward offset in mm.",
            );
            point_list(
                ui,
                &format!("v{l}"),
                &mut v.points,
                ["t", "offset"],
                ["", " mm"],
                2,
            );
        },
    );
    let new_horizontal = || HorizontalLine {
        at: 1.0,
        reach: 0.3,
        points: vec![[0.0, 0.0], [90.0, 5.0], [180.0, 0.0], [270.0, 5.0]],
    };
    removable_groups(
        ui,
        &mut d.control.horizontal,
        "Horizontal line",
        "+ horizontal line",
        new_horizontal,
        |ui, l, h| {
            number(
                ui,
                "At",
                &mut h.at,
                "",
                0.0..=1.0,
                "Height fraction where the line acts fully.",
            );
            number(
                ui,
                "Reach",
                &mut h.reach,
                "",
                0.001..=1.0,
                "Height fraction over which the effect fades out.",
            );
            explain(
                ui,
                "Points: angle in degrees and the z offset in mm (a wavy rim).",
            );
            point_list(
                ui,
                &format!("h{l}"),
                &mut h.points,
                ["angle", "dz"],
                ["°", " mm"],
                2,
            );
        },
    );
}

/// A list of items, each in its own group titled "`title` i" with a remove button, and a button
/// that adds `new()` at the end.
fn removable_groups<T>(
    ui: &mut egui::Ui,
    items: &mut Vec<T>,
    title: &str,
    add_label: &str,
    new: impl FnOnce() -> T,
    mut body: impl FnMut(&mut egui::Ui, usize, &mut T),
) {
    let mut remove = None;
    for (i, item) in items.iter_mut().enumerate() {
        ui.group(|ui| {
            ui.horizontal(|ui| {
                ui.strong(format!("{title} {i}"));
                if ui.small_button("remove").clicked() {
                    remove = Some(i);
                }
            });
            body(ui, i, item);
        });
    }
    if let Some(i) = remove {
        items.remove(i);
    }
    if ui.button(add_label).clicked() {
        items.push(new());
    }
}

fn wave(ui: &mut egui::Ui, id: &str, w: &mut Option<Wave>, period_unit: &str) {
    let mut on = w.is_some();
    if ui.checkbox(&mut on, format!("{id} wave")).changed() {
        *w = on.then_some(Wave {
            wave: WaveKind::Sine,
            period: 10.0,
            amplitude: 1.0,
        });
    }
    if let Some(w) = w {
        egui::ComboBox::from_id_salt(format!("{id} wave kind"))
            .selected_text(format!("{:?}", w.wave).to_lowercase())
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut w.wave, WaveKind::Sine, "sine");
                ui.selectable_value(&mut w.wave, WaveKind::Triangle, "triangle");
                ui.selectable_value(&mut w.wave, WaveKind::Square, "square");
            });
        field_as_at(
            ui,
            "wave.period",
            &format!("texture.{id}.period"),
            &mut w.period,
            Some(period_unit),
        );
        field_as_at(
            ui,
            "wave.amplitude",
            &format!("texture.{id}.amplitude"),
            &mut w.amplitude,
            None,
        );
    }
}

fn texture(ui: &mut egui::Ui, t: &mut Option<Texture>) {
    explain(
        ui,
        "Periodic waves pressed into the wall along its normal: x runs around the vessel, y up it.",
    );
    let mut on = t.is_some();
    if ui.checkbox(&mut on, "textured").changed() {
        *t = on.then_some(Texture {
            combine: Combine::Product,
            x: Some(Wave {
                wave: WaveKind::Sine,
                period: 20.0,
                amplitude: 1.0,
            }),
            y: None,
            phase_drift: 0.0,
            start: 0.0,
            end: 1.0,
        });
    }
    let Some(t) = t else { return };
    egui::ComboBox::from_id_salt("combine")
        .selected_text(format!("{:?}", t.combine).to_lowercase())
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut t.combine, Combine::Product, "product");
            ui.selectable_value(&mut t.combine, Combine::Sum, "sum");
        });
    wave(ui, "x", &mut t.x, "samples");
    wave(ui, "y", &mut t.y, "layers");
    field(ui, "texture.phase_drift", &mut t.phase_drift);
    field(ui, "texture.start", &mut t.start);
    field(ui, "texture.end", &mut t.end);
}

/// Picks one of the shipped printer profiles: its settings replace the printer's (as a slicer
/// does when another printer is chosen); the design keeps its shape.
fn printer_picker(ui: &mut egui::Ui, d: &mut Design) {
    let current = d.printer.profile.clone().unwrap_or_else(|| "custom".into());
    let mut chosen: Option<&str> = None;
    egui::ComboBox::from_label("Printer")
        .selected_text(current.clone())
        .show_ui(ui, |ui| {
            for (name, _) in clayloft_core::profile::SHIPPED {
                if ui.selectable_label(current == *name, *name).clicked() {
                    chosen = Some(name);
                }
            }
        })
        .response
        .on_hover_text("A profile of a real clay printer: bed, build height, nozzle, layers, speeds, firmware, start and end G-code.");
    if let Some(name) = chosen
        && let Some((_, text)) = clayloft_core::profile::SHIPPED
            .iter()
            .find(|(n, _)| *n == name)
        && let Ok(file) = clayloft_core::profile::parse_shipped(name, text)
    {
        let mut printer = file.printer;
        printer.profile = Some(name.to_string());
        d.printer = printer;
        // A placement made for the old bed need not lie on the new one.
        d.shape.center = None;
    }
    let p = &d.printer;
    ui.label(match p.bed_shape {
        clayloft_core::design::BedShape::Rectangle => format!(
            "bed {} × {} mm, origin {}",
            p.bed_x,
            p.bed_y,
            p.origin.name()
        ),
        clayloft_core::design::BedShape::Circle => format!(
            "round bed {} mm across, origin {}",
            p.bed_x,
            p.origin.name()
        ),
    });
}

fn printer(ui: &mut egui::Ui, d: &mut Design) {
    printer_picker(ui, d);
    let p = &mut d.printer;
    explain(
        ui,
        "Defaults are the paper's clay printer. Layer limits keep the bead stacked; speeds set the print time.",
    );
    field(ui, "printer.bed_x", &mut p.bed_x);
    field(ui, "printer.bed_y", &mut p.bed_y);
    field(ui, "printer.max_z", &mut p.max_z);
    field(ui, "printer.nozzle_diameter", &mut p.nozzle_diameter);
    field(ui, "printer.line_width", &mut p.line_width);
    field(ui, "printer.layer_height", &mut p.layer_height);
    field(ui, "printer.min_layer_height", &mut p.min_layer_height);
    field(ui, "printer.max_layer_height", &mut p.max_layer_height);
    field(ui, "printer.nozzle_length", &mut p.nozzle_length);
    field(ui, "printer.max_overhang_deg", &mut p.max_overhang_deg);
    field(ui, "printer.print_speed", &mut p.print_speed);
    field(ui, "printer.travel_speed", &mut p.travel_speed);
    field(ui, "printer.max_acceleration", &mut p.max_acceleration);
    field(ui, "printer.junction_deviation", &mut p.junction_deviation);
    field(ui, "printer.feed_diameter", &mut p.feed_diameter);
    field(ui, "printer.flow_multiplier", &mut p.flow_multiplier);
    field(ui, "printer.min_layer_time", &mut p.min_layer_time);
    field(ui, "printer.flow_ramp_start", &mut p.flow_ramp_start);
    field(ui, "printer.flow_ramp_end", &mut p.flow_ramp_end);
    ui.horizontal(|ui| {
        ui.label("Extrusion")
            .on_hover_text("E values per move (M83) or cumulative (M82).");
        ui.selectable_value(&mut p.extrusion, ExtrusionMode::Relative, "relative");
        ui.selectable_value(&mut p.extrusion, ExtrusionMode::Absolute, "absolute");
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    fn design() -> Design {
        clayloft_core::load::parse_design(
            "version = 1\n[shape]\nheight = 60.0\nlower = { type = \"circle\", radius = 40.0 }\nupper = { type = \"circle\", radius = 45.0 }\n",
        )
        .unwrap()
    }

    fn form() -> Harness<'static, Design> {
        form_of(design())
    }

    /// The form on `design`, with the validator's problems of it as the app would pass them.
    fn form_of(design: Design) -> Harness<'static, Design> {
        Harness::builder()
            .with_size(egui::vec2(420.0, 4000.0))
            .build_ui_state(
                |ui, d: &mut Design| {
                    let status = ModelStatus {
                        errors: clayloft_core::validate::validate_all(d),
                    };
                    design_form(ui, d, None, &status)
                },
                design,
            )
    }

    #[test]
    fn a_design_from_a_mesh_shows_the_mesh_not_contours() {
        let mut d = design();
        d.shape.mesh = Some(clayloft_core::design::MeshSource {
            path: "vase.stl".into(),
            scale: 1.0,
            rotate_x: 0.0,
        });
        let mut h = form_of(d);
        h.run();
        assert!(h.query_by_label("file: vase.stl").is_some());
        assert!(h.query_by_label("Scale").is_some());
        assert!(h.query_by_label("Lower contour (on the bed)").is_none());
        assert!(h.query_by_label("Control lines").is_none());
    }

    #[test]
    fn an_invalid_value_is_said_next_to_its_field_and_kept() {
        // Out of range: said under the field, not clamped away.
        let mut d = design();
        d.shape.height = -5.0;
        d.shape.samples = 0;
        let mut h = form_of(d);
        h.run();
        assert_eq!(h.state().shape.height, -5.0, "the value is kept as typed");
        assert_eq!(h.state().shape.samples, 0);
        assert!(h.query_by_label_contains("-5 mm is outside").is_some());
        assert!(h.query_by_label_contains("0 is outside 3").is_some());
        // In range but refused with another field: the validator's words under the field.
        let mut d = design();
        d.printer.max_z = 50.0;
        let mut h = form_of(d);
        h.run();
        assert!(
            h.query_by_label_contains("taller than the printer's build height")
                .is_some()
        );
        // A valid design shows no problem.
        let mut h = form();
        h.run();
        assert!(h.query_by_label_contains("is outside").is_none());
    }

    #[test]
    fn control_lines_are_added_and_removed_from_the_form() {
        let mut h = form();
        h.get_by_label("Control lines").click();
        h.run();
        h.get_by_label("+ vertical line").click();
        h.run();
        h.get_by_label("+ vertical line").click();
        h.run();
        h.get_by_label("+ horizontal line").click();
        h.run();
        assert_eq!(h.state().control.vertical.len(), 2);
        assert_eq!(h.state().control.horizontal.len(), 1);
        assert!(h.query_by_label("Vertical line 1").is_some());
        assert!(h.query_by_label("Horizontal line 0").is_some());
        // The new lines make a valid design: the pipeline runs it.
        assert!(clayloft_core::run(h.state()).is_ok());
        // "remove" on the first group takes the first vertical line away.
        h.get_all_by_label("remove").next().unwrap().click();
        h.run();
        assert_eq!(h.state().control.vertical.len(), 1);
        assert_eq!(h.state().control.horizontal.len(), 1);
        assert!(h.query_by_label("Vertical line 1").is_none());
    }

    #[test]
    fn a_contour_type_and_a_texture_are_chosen_from_the_form() {
        let mut h = form();
        // The lower contour's type box shows "circle" (the upper one too: take the first).
        h.get_all_by_value("circle").next().unwrap().click();
        h.run();
        h.get_by_label("star").click();
        h.run();
        assert!(matches!(
            h.state().shape.lower,
            ContourSpec::Star { points: 5, .. }
        ));
        assert!(matches!(h.state().shape.upper, ContourSpec::Circle { .. }));
        h.get_by_label("Texture").click();
        h.run();
        h.get_by_label("textured").click();
        h.run();
        let texture = h.state().texture.clone().expect("a texture");
        assert_eq!(texture.x.map(|w| w.period), Some(20.0));
        assert!(clayloft_core::run(h.state()).is_ok());
    }

    #[test]
    fn a_printer_is_picked_from_the_form_and_the_design_prints_on_it() {
        let mut h = form();
        h.get_by_label("Printer").click(); // open the section
        h.run();
        h.get_by_value("custom").click(); // the picker shows the design's printer
        h.run();
        h.get_by_label("wasp-2040-clay").click();
        h.run();
        let p = &h.state().printer;
        assert_eq!(p.profile.as_deref(), Some("wasp-2040-clay"));
        assert_eq!(p.bed_shape, clayloft_core::design::BedShape::Circle);
        assert_eq!((p.bed_x, p.bed_y), (200.0, 200.0));
        assert!(
            h.query_by_label_contains("round bed 200 mm across, origin centre")
                .is_some()
        );
        // The vessel stands at the centre of the round bed and prints there.
        assert_eq!(h.state().center(), [100.0, 100.0]);
        let job = clayloft_core::run(h.state()).expect("the design prints on the delta");
        assert!(!job.toolpath.points.is_empty());
    }
}
