//! The flow view (SPEC §8 "Teaching", §10): the clay in the screw groove, simulated live on a
//! background thread while the student changes the screw speed, the groove and the material.
//! Speed as colour with streamlines, u and v along the centre lines as plots (egui_plot), the
//! vortex centre and the dead zones, with short explanations.

use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use clayloft_flow::analysis::{
    dead_cells, speed_colour, streamlines, unyielded_fraction, vortex_centre,
};
use clayloft_flow::groove::{Groove, MATERIALS, Material};
use clayloft_ui::{Corner, toggle_on_title_click, tool_window};

/// The window's title.
const FLOW_WINDOW: &str = "Extruder flow";

/// Lattice cells across the groove in the live view (the command line defaults to 120): fine
/// enough to show the corner eddies, coarse enough to converge in a few seconds on one core.
const CELLS: usize = 64;

/// The settings a student changes: the screw and groove, and the slurry — a preset
/// ([`MATERIALS`]) whose yield stress, consistency and flow index can then be changed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowSettings {
    pub rpm: f64,
    pub diameter_mm: f64,
    pub width_mm: f64,
    pub depth_mm: f64,
    /// The preset the slurry started from (its density and source).
    pub material: usize,
    /// Yield stress τ₀ (Pa), consistency K (Pa·sⁿ), flow index n.
    pub tau0: f64,
    pub k: f64,
    pub n: f64,
}

impl FlowSettings {
    /// The default groove with preset `material`.
    pub fn with_material(material: usize) -> FlowSettings {
        let m = MATERIALS[material.min(MATERIALS.len() - 1)];
        FlowSettings {
            rpm: 45.0,
            diameter_mm: 20.0,
            width_mm: 4.0,
            depth_mm: 4.0,
            material,
            tau0: m.tau0,
            k: m.k,
            n: m.n,
        }
    }

    /// The slurry: the preset with the chosen τ₀, K and n.
    pub fn slurry(&self) -> Material {
        Material {
            tau0: self.tau0,
            k: self.k,
            n: self.n,
            ..MATERIALS[self.material.min(MATERIALS.len() - 1)]
        }
    }

    /// The same screw and groove with preset `material`'s slurry.
    fn with_preset(&self, material: usize) -> FlowSettings {
        let m = FlowSettings::with_material(material);
        FlowSettings {
            material,
            tau0: m.tau0,
            k: m.k,
            n: m.n,
            ..*self
        }
    }

    /// Whether τ₀, K and n are still the preset's.
    fn is_preset(&self) -> bool {
        self.slurry() == MATERIALS[self.material.min(MATERIALS.len() - 1)]
    }
}

impl Default for FlowSettings {
    fn default() -> Self {
        FlowSettings::with_material(2)
    }
}

/// A picture of the running simulation.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub nx: usize,
    pub ny: usize,
    /// Velocities in units of the wall speed, row-major from the bottom.
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub steps: u64,
    pub change: f64,
    /// Share of the cells whose shear stress stays below the yield stress.
    pub unyielded: f64,
    pub reynolds: f64,
    pub bingham: f64,
    pub cell_mm: f64,
    /// Streamlines in cells (x, y from the lower left).
    pub lines: Vec<Vec<(f64, f64)>>,
}

struct Run {
    settings: FlowSettings,
    stop: Arc<AtomicBool>,
    rx: Mutex<Receiver<Snapshot>>,
}

/// The window's state.
#[derive(Resource, Default)]
pub struct FlowView {
    /// Whether the window starts expanded (it starts collapsed, and simulates nothing until
    /// the student opens it).
    pub open: bool,
    pub settings: FlowSettings,
    run: Option<Run>,
    pub last: Option<Snapshot>,
    texture: Option<egui::TextureHandle>,
}

impl FlowView {
    /// The window expanded from the start, running the default settings.
    pub fn opened() -> FlowView {
        FlowView {
            open: true,
            ..Default::default()
        }
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// Starts the solver for `s` on its own thread; it sends a snapshot every 500 steps until it
/// converges or is stopped.
fn start(s: FlowSettings) -> Run {
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = channel();
    let flag = stop.clone();
    std::thread::spawn(move || {
        let g = Groove {
            width_m: s.width_mm * 1e-3,
            depth_m: s.depth_mm * 1e-3,
            screw_diameter_m: s.diameter_mm * 1e-3,
            rpm: s.rpm,
            material: s.slurry(),
        };
        let l = g.to_lattice(CELLS, 1.0);
        let mut solver = l.solver();
        let mut prev: Option<Vec<f64>> = None;
        while !flag.load(Ordering::Relaxed) {
            solver.advance(500);
            let (u, v) = solver.velocity();
            let change = prev
                .as_ref()
                .map(|p| {
                    p.iter()
                        .zip(&u)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                        / l.lid_u
                })
                .unwrap_or(1.0);
            prev = Some(u.clone());
            let snap = Snapshot {
                nx: l.nx,
                ny: l.ny,
                u: u.iter().map(|x| x / l.lid_u).collect(),
                v: v.iter().map(|x| x / l.lid_u).collect(),
                steps: solver.steps,
                change,
                unyielded: unyielded_fraction(&solver.shear_stresses(), l.yield_stress()),
                reynolds: l.reynolds,
                bingham: l.bingham,
                cell_mm: l.dx * 1e3,
                lines: streamlines(&u, &v, l.nx, l.ny, 7, 1e-4 * l.lid_u),
            };
            if tx.send(snap).is_err() || (change < 1e-6 && solver.steps > 20_000) {
                break;
            }
        }
    });
    Run {
        settings: s,
        stop,
        rx: Mutex::new(rx),
    }
}

pub struct FlowViewPlugin;

impl Plugin for FlowViewPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<FlowView>().add_systems(
            EguiPrimaryContextPass,
            draw_flow_window.in_set(clayloft_ui::UiSystems::Windows),
        );
    }
}

/// Speed as colour: dark blue (still) to yellow (the wall's speed).
fn speed_image(s: &Snapshot) -> egui::ColorImage {
    let mut img = egui::ColorImage::new([s.nx, s.ny], vec![egui::Color32::BLACK; s.nx * s.ny]);
    for y in 0..s.ny {
        for x in 0..s.nx {
            let k = y * s.nx + x;
            let [r, g, b] = speed_colour(s.u[k].hypot(s.v[k]));
            img.pixels[(s.ny - 1 - y) * s.nx + x] = egui::Color32::from_rgb(r, g, b);
        }
    }
    img
}

/// The speed picture with the streamlines drawn over it.
fn speed_with_streamlines(ui: &mut egui::Ui, tex: &egui::TextureHandle, snap: &Snapshot) {
    let size = egui::vec2(200.0, 200.0 * snap.ny as f32 / snap.nx as f32);
    let response = ui.image((tex.id(), size));
    let rect = response.rect;
    let painter = ui.painter_at(rect);
    let to_screen = |(x, y): (f64, f64)| {
        egui::pos2(
            rect.left() + (x / snap.nx as f64) as f32 * rect.width(),
            rect.bottom() - (y / snap.ny as f64) as f32 * rect.height(),
        )
    };
    let stroke = egui::Stroke::new(1.0, egui::Color32::from_white_alpha(170));
    for line in &snap.lines {
        painter.add(egui::Shape::line(
            line.iter().map(|p| to_screen(*p)).collect(),
            stroke,
        ));
    }
    response.on_hover_text(
        "Colour: speed, from still (dark blue) to the barrel's speed (yellow). White lines: streamlines, the paths the clay follows.",
    );
}

/// A centre-line plot: `points` are (position across the groove 0…1, velocity in wall speeds);
/// drawn with the position upwards when `vertical` (u along the vertical centre line).
fn centre_line_plot(
    ui: &mut egui::Ui,
    id: &str,
    title: &str,
    points: &[(f64, f64)],
    vertical: bool,
) {
    use egui_plot::{Line, Plot};
    let series: Vec<[f64; 2]> = points
        .iter()
        .map(|&(t, val)| if vertical { [val, t] } else { [t, val] })
        .collect();
    let (x_label, y_label) = if vertical {
        ("u / wall speed", "height / depth")
    } else {
        ("position / width", "v / wall speed")
    };
    ui.vertical(|ui| {
        ui.label(title);
        Plot::new(id)
            .width(155.0)
            .height(180.0)
            .x_axis_label(x_label)
            .y_axis_label(y_label)
            .include_x(if vertical { -0.5 } else { 0.0 })
            .include_x(1.0)
            .include_y(if vertical { 0.0 } else { -0.5 })
            .include_y(if vertical { 1.0 } else { 0.5 })
            .allow_drag(false)
            .allow_zoom(false)
            .allow_scroll(false)
            .show(ui, |plot| {
                plot.line(
                    Line::new(title, series)
                        .color(egui::Color32::from_rgb(240, 180, 60))
                        .width(2.0),
                );
            });
    });
}

fn draw_flow_window(mut contexts: EguiContexts, mut view: ResMut<FlowView>) -> Result {
    let ctx = contexts.ctx_mut()?.clone();
    let view = &mut *view;
    if view.run.is_some() {
        // Snapshots arrive from the simulation thread: keep frames coming while it runs.
        ctx.request_repaint();
    }
    let opened = view.open;
    tool_window(&ctx, FLOW_WINDOW, Corner::TopRight, opened)
        .max_width(580.0)
        .show(&ctx, |ui| {
        ui.label(egui::RichText::new(
            "The clay inside one turn of the extruder's screw groove, seen in cross-section. The barrel (top) slides over the groove as the screw turns and drags the clay round in a vortex; clay in the lower corners barely moves (dead zones). A yield-stress slurry only flows where it is sheared hard enough.",
        ).small().weak());
        let s = &mut view.settings;
        ui.add(egui::Slider::new(&mut s.rpm, 5.0..=120.0).text("screw speed, rpm"));
        ui.add(egui::Slider::new(&mut s.diameter_mm, 5.0..=60.0).text("screw diameter, mm"));
        ui.add(egui::Slider::new(&mut s.width_mm, 1.0..=10.0).text("groove width, mm"));
        ui.add(egui::Slider::new(&mut s.depth_mm, 1.0..=10.0).text("groove depth, mm"));
        let name = MATERIALS[s.material].name;
        let label = if s.is_preset() { name.to_string() } else { format!("{name}, changed") };
        egui::ComboBox::from_label("material").selected_text(label).show_ui(ui, |ui| {
            for (i, m) in MATERIALS.iter().enumerate() {
                if ui.selectable_label(s.material == i && s.is_preset(), m.name).on_hover_text(m.source).clicked() {
                    *s = s.with_preset(i);
                }
            }
        });
        ui.add(egui::Slider::new(&mut s.tau0, 0.0..=2000.0).text("yield stress τ₀, Pa"))
            .on_hover_text("Below this stress the slurry stands still like a soft solid; above it, it flows. 0 = no yield stress.");
        ui.add(egui::Slider::new(&mut s.k, 0.1..=2000.0).logarithmic(true).text("consistency K, Pa·s^n"))
            .on_hover_text("How thick the slurry is: its viscosity at a shear rate of 1 per second.");
        ui.add(egui::Slider::new(&mut s.n, 0.1..=1.5).text("flow index n"))
            .on_hover_text("Below 1 the slurry thins the faster it is sheared (clay does); 1 is a plain (Newtonian) liquid; above 1 it thickens.");
        let settings = *s;
        if view.run.as_ref().map(|r| r.settings) != Some(settings) {
            view.run = Some(start(settings));
        }
        if let Some(run) = &view.run
            && let Ok(rx) = run.rx.lock()
            && let Some(snap) = rx.try_iter().last()
        {
            view.texture = Some(ctx.load_texture("flow speed", speed_image(&snap), egui::TextureOptions::NEAREST));
            view.last = Some(snap);
        }
        let Some(snap) = &view.last else {
            ui.label("starting…");
            return;
        };
        ui.horizontal_wrapped(|ui| {
            if let Some(tex) = &view.texture {
                speed_with_streamlines(ui, tex, snap);
            }
            let (nx, ny) = (snap.nx, snap.ny);
            let ucol: Vec<(f64, f64)> = (0..ny).map(|y| ((y as f64 + 0.5) / ny as f64, snap.u[y * nx + nx / 2])).collect();
            let vrow: Vec<(f64, f64)> = (0..nx).map(|x| ((x as f64 + 0.5) / nx as f64, snap.v[(ny / 2) * nx + x])).collect();
            centre_line_plot(ui, "flow u", "u along the vertical centre line", &ucol, true);
            centre_line_plot(ui, "flow v", "v along the horizontal centre line", &vrow, false);
        });
        ui.label(egui::RichText::new(
            "u: the clay under the barrel moves with it (u = 1 at the top) and flows back lower down (u < 0) — what goes round must come back. v: up on one side, down on the other: the vortex.",
        ).small().weak());
        let (cx, cy) = vortex_centre(&snap.u, snap.nx, snap.ny);
        let (l, r) = dead_cells(&snap.u, &snap.v, snap.nx, snap.ny, 0.01);
        let a = snap.cell_mm * snap.cell_mm;
        ui.label(format!(
            "Reynolds number {:.1e} (viscous: inertia plays no part) · Bingham number {:.1} · vortex centre ({:.2}, {:.2}) mm · dead zones {:.2} / {:.2} mm² · {:.0} % of the slurry unyielded",
            snap.reynolds,
            snap.bingham,
            cx * snap.nx as f64 * snap.cell_mm,
            cy * snap.ny as f64 * snap.cell_mm,
            l as f64 * a,
            r as f64 * a,
            snap.unyielded * 100.0
        ));
        ui.label(egui::RichText::new(
            "Bingham number: the yield stress against the stress the barrel's shearing makes. The slower the screw, the larger it is, and the more of the slurry stands still (unyielded: its stress stays below the yield stress).",
        ).small().weak());
        let state = if snap.change < 1e-6 { "converged" } else { "running" };
        ui.label(egui::RichText::new(format!("{state}: {} steps, change {:.1e}", snap.steps, snap.change)).small().weak());
    });
    toggle_on_title_click(&ctx, FLOW_WINDOW, opened);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_changed_slurry_keeps_its_preset_for_the_rest() {
        let mut s = FlowSettings::with_material(1);
        assert!(s.is_preset());
        assert_eq!(s.slurry(), MATERIALS[1]);
        s.tau0 = 150.0;
        assert!(!s.is_preset());
        let m = s.slurry();
        assert_eq!(
            (m.tau0, m.k, m.n, m.rho),
            (150.0, MATERIALS[1].k, MATERIALS[1].n, MATERIALS[1].rho)
        );
        // Picking a preset again keeps the screw and groove and restores its slurry.
        let t = FlowSettings { rpm: 90.0, ..s }.with_preset(2);
        assert_eq!((t.rpm, t.material), (90.0, 2));
        assert!(t.is_preset());
    }

    #[test]
    fn the_background_run_sends_snapshots_and_stops_when_dropped() {
        let run = start(FlowSettings::with_material(0));
        let snap = run
            .rx
            .lock()
            .unwrap()
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("a snapshot");
        assert_eq!((snap.nx, snap.ny), (CELLS, CELLS));
        assert_eq!(snap.steps, 500);
        // The wall drags the top row along: u near 1 under the lid, and the image has a pixel per cell.
        let top = snap.u[(snap.ny - 1) * snap.nx + snap.nx / 2];
        assert!(top > 0.3, "{top}");
        assert_eq!(speed_image(&snap).pixels.len(), CELLS * CELLS);
        // Later, the streamlines circle the vortex: some line reaches both the upper and the
        // lower half of the groove.
        let rx = run.rx.lock().unwrap();
        let later = loop {
            let snap = rx
                .recv_timeout(std::time::Duration::from_secs(60))
                .expect("more snapshots");
            if snap.steps >= 20_000 {
                break snap;
            }
        };
        let mid = CELLS as f64 / 2.0;
        assert!(
            later
                .lines
                .iter()
                .any(|l| l.iter().any(|p| p.1 > mid + 5.0) && l.iter().any(|p| p.1 < mid - 5.0)),
            "{} streamlines, none round the vortex",
            later.lines.len()
        );
        drop(rx);
        drop(run);
    }
}
