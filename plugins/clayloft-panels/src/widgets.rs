//! Small labelled inputs with units and an explanation on hover.

use bevy_egui::egui;

/// Where the form keeps the problems of the design being edited for this frame (egui's
/// per-frame data), so that each field can show its own next to it.
const FIELD_PROBLEMS: &str = "clayloft field problems";

/// Makes `problems` (dotted field path, message) known to the fields drawn after it.
pub fn set_field_problems(ui: &egui::Ui, problems: Vec<(String, String)>) {
    ui.data_mut(|d| d.insert_temp(egui::Id::new(FIELD_PROBLEMS), problems));
}

/// The validator's problem with the field at `path`, if any.
fn problem_of(ui: &egui::Ui, path: &str) -> Option<String> {
    ui.data(|d| d.get_temp::<Vec<(String, String)>>(egui::Id::new(FIELD_PROBLEMS)))
        .and_then(|all| all.into_iter().find(|(p, _)| p == path).map(|(_, m)| m))
}

const PROBLEM: egui::Color32 = egui::Color32::from_rgb(255, 90, 90);
const HELD: egui::Color32 = egui::Color32::from_rgb(240, 200, 90);

/// A value outside `range`, said under its field: a drag past the end is held at the limit (and
/// says so while it is held); a typed value is kept as typed, so the validator's error shows
/// (the vessel stays the last good one until it is fixed). Nothing is changed silently.
fn say_range<T: PartialOrd + Copy + std::fmt::Display>(
    ui: &mut egui::Ui,
    v: &mut T,
    range: &std::ops::RangeInclusive<T>,
    unit: &str,
    dragged: bool,
    path: Option<&str>,
) {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    let (lo, hi) = (*range.start(), *range.end());
    if dragged && !range.contains(v) {
        *v = if *v < lo { lo } else { hi };
        ui.colored_label(
            HELD,
            format!("held at {}{unit}: the limit ({lo} … {hi}{unit})", *v),
        );
    } else if !range.contains(v) {
        ui.colored_label(
            PROBLEM,
            format!("{}{unit} is outside {lo} … {hi}{unit}", *v),
        );
    } else if let Some(m) = path.and_then(|p| problem_of(ui, p)) {
        ui.colored_label(PROBLEM, m);
    }
}

/// A number with its unit; the explanation shows when hovering the label or the value. Out of
/// `range` it is said, not clamped ([`say_range`]).
pub fn number(
    ui: &mut egui::Ui,
    label: &str,
    v: &mut f64,
    unit: &str,
    range: std::ops::RangeInclusive<f64>,
    help: &str,
) {
    number_at(ui, None, label, v, unit, range, help);
}

fn number_at(
    ui: &mut egui::Ui,
    path: Option<&str>,
    label: &str,
    v: &mut f64,
    unit: &str,
    range: std::ops::RangeInclusive<f64>,
    help: &str,
) {
    let mut dragged = false;
    ui.horizontal(|ui| {
        ui.label(label).on_hover_text(help);
        let speed = ((range.end() - range.start()) / 500.0).clamp(0.001, 1.0);
        dragged =
            ui.add(egui::DragValue::new(v).speed(speed).max_decimals(3).suffix(
                if unit.is_empty() {
                    String::new()
                } else {
                    format!(" {unit}")
                },
            ))
            .on_hover_text(help)
            .dragged();
    });
    say_range(ui, v, &range, unit, dragged, path);
}

/// A number of the design described once in the core ([`clayloft_core::fields`]): its label,
/// unit, valid range and explanation are the validator's, and so is the problem shown under it.
pub fn field(ui: &mut egui::Ui, path: &str, v: &mut f64) {
    let m = clayloft_core::fields::meta(path);
    number_at(ui, Some(path), m.label, v, m.unit, m.form_range(), m.help);
}

/// A number whose meaning is a shared entry of [`clayloft_core::fields`] (`contour.radius`,
/// `wave.amplitude`), with the unit given where it depends on the context, for the field at
/// dotted `path` of the design (the validator's problem with it shows under it).
pub fn field_as_at(ui: &mut egui::Ui, entry: &str, path: &str, v: &mut f64, unit: Option<&str>) {
    let m = clayloft_core::fields::meta(entry);
    number_at(
        ui,
        Some(path),
        m.label,
        v,
        unit.unwrap_or(m.unit),
        m.form_range(),
        m.help,
    );
}

/// A whole number of the design at dotted `path` (its validator problem shown under it), out of
/// `range` said, not clamped.
pub fn count(
    ui: &mut egui::Ui,
    path: &str,
    label: &str,
    v: &mut usize,
    range: std::ops::RangeInclusive<usize>,
    help: &str,
) {
    let mut dragged = false;
    ui.horizontal(|ui| {
        ui.label(label).on_hover_text(help);
        dragged = ui
            .add(egui::DragValue::new(v).speed(0.2))
            .on_hover_text(help)
            .dragged();
    });
    say_range(ui, v, &range, "", dragged, Some(path));
}

/// A short explanation under a group, for students.
pub fn explain(ui: &mut egui::Ui, text: &str) {
    ui.label(egui::RichText::new(text).small().weak());
}

/// A list of 2-D points: one row per point with remove buttons, and "add point" that inserts a
/// copy of the point before it (or the midpoint of the last two).
pub fn point_list(
    ui: &mut egui::Ui,
    id: &str,
    points: &mut Vec<[f64; 2]>,
    names: [&str; 2],
    units: [&str; 2],
    min_points: usize,
) {
    let mut remove = None;
    let mut insert = None;
    egui::Grid::new(id)
        .num_columns(4)
        .striped(true)
        .show(ui, |ui| {
            for (i, p) in points.iter_mut().enumerate() {
                ui.label(format!("{i}"));
                ui.add(
                    egui::DragValue::new(&mut p[0])
                        .speed(0.05)
                        .max_decimals(3)
                        .prefix(format!("{} ", names[0]))
                        .suffix(units[0]),
                );
                ui.add(
                    egui::DragValue::new(&mut p[1])
                        .speed(0.05)
                        .max_decimals(3)
                        .prefix(format!("{} ", names[1]))
                        .suffix(units[1]),
                );
                ui.horizontal(|ui| {
                    if ui
                        .small_button("+")
                        .on_hover_text("insert a point after this one")
                        .clicked()
                    {
                        insert = Some(i);
                    }
                    if ui
                        .small_button("−")
                        .on_hover_text("remove this point")
                        .clicked()
                    {
                        remove = Some(i);
                    }
                });
                ui.end_row();
            }
        });
    if let Some(i) = insert {
        let a = points[i];
        let b = points.get(i + 1).copied().unwrap_or(points[0]);
        points.insert(i + 1, [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]);
    }
    if let Some(i) = remove
        && points.len() > min_points
    {
        points.remove(i);
    }
}
