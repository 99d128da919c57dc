//! "Load contour from image / SVG": a window per image or SVG contour showing the picture with
//! the outline traced from it (or the drawing's outline), so the user sees what will be printed
//! while moving the threshold; errors (missing file, blank picture, …) are shown in red.

use std::path::PathBuf;

use bevy_egui::egui;
use clayloft_core::Design;
use clayloft_core::design::ContourSpec;
use clayloft_core::outline::resolve;
use clayloft_core::trace;
use clayloft_ui::{Corner, toggle_on_title_click, tool_window};

/// Largest side of the picture shown, pixels.
const PREVIEW_SIDE: u32 = 220;

/// What one preview window shows, recomputed only when its source changes.
#[derive(Default)]
pub struct SourcePreview {
    key: Option<(PathBuf, ContourSpec)>,
    texture: Option<egui::TextureHandle>,
    /// Outline in the shown picture's pixels (images) or in the drawing's units (SVG).
    outline: Vec<egui::Pos2>,
    /// Size of the picture or the drawing's outline box, in the same units.
    size: egui::Vec2,
    message: Option<(String, bool)>,
}

impl SourcePreview {
    fn refresh(
        &mut self,
        ctx: &egui::Context,
        name: &str,
        spec: &ContourSpec,
        base: Option<&std::path::Path>,
    ) {
        let path = match spec {
            ContourSpec::Image { path, .. } | ContourSpec::Svg { path, .. } => resolve(path, base),
            _ => return,
        };
        let key = (path.clone(), spec.clone());
        if self.key.as_ref() == Some(&key) {
            return;
        }
        self.key = Some(key);
        self.texture = None;
        self.outline.clear();
        match spec {
            ContourSpec::Image { threshold, .. } => {
                match trace::preview(&path, *threshold, PREVIEW_SIDE) {
                    Ok(p) => {
                        let (w, h) = p.thumbnail.dimensions();
                        let img = egui::ColorImage::from_gray(
                            [w as usize, h as usize],
                            p.thumbnail.as_raw(),
                        );
                        self.texture = Some(ctx.load_texture(
                            format!("{name} picture"),
                            img,
                            egui::TextureOptions::LINEAR,
                        ));
                        self.size = egui::vec2(w as f32, h as f32);
                        match p.outline {
                            Ok(t) => {
                                self.outline = t
                                    .points
                                    .iter()
                                    .map(|q| {
                                        egui::pos2((q.x * p.scale) as f32, (q.y * p.scale) as f32)
                                    })
                                    .collect();
                                let tone = if t.dark_on_light {
                                    "dark shape on light"
                                } else {
                                    "light shape on dark"
                                };
                                self.message = Some((
                                    format!(
                                        "threshold {} ({tone}), {} outline points, {:.0} px² enclosed",
                                        t.threshold,
                                        t.points.len(),
                                        t.area_px
                                    ),
                                    false,
                                ));
                            }
                            Err(e) => self.message = Some((e.to_string(), true)),
                        }
                    }
                    Err(e) => self.message = Some((format!("{}: {e}", path.display()), true)),
                }
            }
            ContourSpec::Svg { id, .. } => {
                let outline = clayloft_core::svg::load_svg(&path)
                    .and_then(|tree| clayloft_core::svg::closed_outline(&tree, id.as_deref()));
                match outline {
                    Ok(pts) => {
                        let (mut lo, mut hi) = (
                            egui::pos2(f32::MAX, f32::MAX),
                            egui::pos2(f32::MIN, f32::MIN),
                        );
                        for q in &pts {
                            lo = lo.min(egui::pos2(q.x as f32, q.y as f32));
                            hi = hi.max(egui::pos2(q.x as f32, q.y as f32));
                        }
                        self.outline = pts
                            .iter()
                            .map(|q| egui::pos2(q.x as f32, q.y as f32) - lo.to_vec2())
                            .collect();
                        self.size = hi - lo;
                        self.message = Some((format!("{} outline points", pts.len()), false));
                    }
                    Err(e) => self.message = Some((format!("{}: {e}", path.display()), true)),
                }
            }
            _ => {}
        }
    }

    fn show(&self, ui: &mut egui::Ui) {
        let scale = (PREVIEW_SIDE as f32 / self.size.x.max(self.size.y).max(1.0))
            .min(1.0)
            .max(if self.texture.is_some() {
                1.0
            } else {
                PREVIEW_SIDE as f32 / self.size.x.max(self.size.y).max(1.0)
            });
        let (rect, _) = ui.allocate_exact_size(self.size * scale, egui::Sense::hover());
        let painter = ui.painter_at(rect);
        if let Some(tex) = &self.texture {
            painter.image(
                tex.id(),
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
        } else {
            painter.rect_filled(rect, 0.0, egui::Color32::from_gray(235));
        }
        if self.outline.len() > 1 {
            let mut pts: Vec<egui::Pos2> = self
                .outline
                .iter()
                .map(|p| rect.min + p.to_vec2() * scale)
                .collect();
            pts.push(pts[0]);
            painter.add(egui::Shape::line(
                pts,
                egui::Stroke::new(2.0, egui::Color32::from_rgb(230, 40, 40)),
            ));
        }
        if let Some((m, err)) = &self.message {
            let c = if *err {
                egui::Color32::from_rgb(255, 90, 90)
            } else {
                egui::Color32::GRAY
            };
            ui.colored_label(c, m);
        }
    }
}

/// One window per image or SVG contour of the design.
pub fn source_windows(ctx: &egui::Context, design: &Design, previews: &mut [SourcePreview; 2]) {
    let base = design.base_dir.as_deref();
    for (i, (label, spec)) in [
        ("Lower contour source", &design.shape.lower),
        ("Upper contour source", &design.shape.upper),
    ]
    .into_iter()
    .enumerate()
    {
        if !matches!(spec, ContourSpec::Image { .. } | ContourSpec::Svg { .. }) {
            previews[i] = SourcePreview::default();
            continue;
        }
        previews[i].refresh(ctx, label, spec, base);
        let corner = [Corner::BottomLeft, Corner::BottomRight][i];
        tool_window(ctx, label, corner, true)
            .resizable(false)
            .show(ctx, |ui| {
                ui.label(egui::RichText::new("The red line is the outline traced from the file; the threshold and size are in the left panel.").small().weak());
                previews[i].show(ui);
            });
        toggle_on_title_click(ctx, label, true);
    }
}
