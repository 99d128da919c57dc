//! Small labelled inputs with units and an explanation on hover.

use bevy_egui::egui;

/// A number with its unit; the explanation shows when hovering the label or the value.
pub fn number(
    ui: &mut egui::Ui,
    label: &str,
    v: &mut f64,
    unit: &str,
    range: std::ops::RangeInclusive<f64>,
    help: &str,
) {
    ui.horizontal(|ui| {
        ui.label(label).on_hover_text(help);
        let speed = ((range.end() - range.start()) / 500.0).clamp(0.001, 1.0);
        ui.add(
            egui::DragValue::new(v)
                .range(range)
                .speed(speed)
                .max_decimals(3)
                .suffix(if unit.is_empty() {
                    String::new()
                } else {
                    format!(" {unit}")
                }),
        )
        .on_hover_text(help);
    });
}

/// A number of the design described once in the core ([`clayloft_core::fields`]): its label,
/// unit, valid range and explanation are the validator's.
pub fn field(ui: &mut egui::Ui, path: &str, v: &mut f64) {
    let m = clayloft_core::fields::meta(path);
    number(ui, m.label, v, m.unit, m.form_range(), m.help);
}

/// A number whose meaning is a shared entry of [`clayloft_core::fields`] (`contour.radius`,
/// `wave.amplitude`), with the unit given where it depends on the context.
pub fn field_as(ui: &mut egui::Ui, entry: &str, v: &mut f64, unit: Option<&str>) {
    let m = clayloft_core::fields::meta(entry);
    number(
        ui,
        m.label,
        v,
        unit.unwrap_or(m.unit),
        m.form_range(),
        m.help,
    );
}

/// A whole number.
pub fn count(
    ui: &mut egui::Ui,
    label: &str,
    v: &mut usize,
    range: std::ops::RangeInclusive<usize>,
    help: &str,
) {
    ui.horizontal(|ui| {
        ui.label(label).on_hover_text(help);
        ui.add(egui::DragValue::new(v).range(range).speed(0.2))
            .on_hover_text(help);
    });
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
