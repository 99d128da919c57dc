//! What the app's egui windows share. The panels (file bar, design form, checks, status line)
//! frame the 3D view; the tool windows (printer, extruder flow, contour sources) float over the
//! view and nowhere else:
//!
//! - [`UiSystems`]: the panels are drawn first and say where the view is ([`set_tool_area`]),
//!   then the windows, which are kept inside it ([`tool_window`]) — so none covers the status
//!   line or a panel;
//! - each tool window has its own corner of the view ([`Corner`]), so their title bars never
//!   cover each other's;
//! - a click on a window's title opens or closes it ([`toggle_on_title_click`]; egui itself
//!   wants a double click).

use bevy::prelude::*;
use bevy_egui::EguiPrimaryContextPass;
use bevy_egui::egui;

/// Order of the egui systems within the frame's egui pass.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UiSystems {
    /// The panels around the view.
    Panels,
    /// The tool windows over the view.
    Windows,
}

/// Orders [`UiSystems`].
pub struct UiPlugin;

impl Plugin for UiPlugin {
    fn build(&self, app: &mut App) {
        app.configure_sets(
            EguiPrimaryContextPass,
            (UiSystems::Panels, UiSystems::Windows).chain(),
        );
    }
}

fn area_id() -> egui::Id {
    egui::Id::new("clayloft tool area")
}

/// Space kept around the view's edge, points.
const MARGIN: f32 = 8.0;

/// Says where the view between the panels is (the panels call this each frame).
pub fn set_tool_area(ctx: &egui::Context, view: egui::Rect) {
    ctx.data_mut(|d| d.insert_temp(area_id(), view.shrink(MARGIN)));
}

/// Where tool windows may be: the view between the panels (the whole window when no panels
/// said otherwise, as in tests).
pub fn tool_area(ctx: &egui::Context) -> egui::Rect {
    ctx.data(|d| d.get_temp::<egui::Rect>(area_id()))
        .unwrap_or_else(|| ctx.viewport_rect().shrink(MARGIN))
}

/// The corner of the view a tool window starts in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Corner {
    TopLeft,
    TopRight,
    BottomLeft,
    BottomRight,
    /// The middle of the bottom edge.
    BottomCentre,
}

impl Corner {
    fn align(self) -> egui::Align2 {
        match self {
            Corner::TopLeft => egui::Align2::LEFT_TOP,
            Corner::TopRight => egui::Align2::RIGHT_TOP,
            Corner::BottomLeft => egui::Align2::LEFT_BOTTOM,
            Corner::BottomRight => egui::Align2::RIGHT_BOTTOM,
            Corner::BottomCentre => egui::Align2::CENTER_BOTTOM,
        }
    }

    /// The point of `area` the window's corner starts at.
    pub fn of(self, area: egui::Rect) -> egui::Pos2 {
        match self {
            Corner::TopLeft => area.left_top(),
            Corner::TopRight => area.right_top(),
            Corner::BottomLeft => area.left_bottom(),
            Corner::BottomRight => area.right_bottom(),
            Corner::BottomCentre => area.center_bottom(),
        }
    }
}

/// A tool window titled `title`: closed at first unless `open`, starting in `corner` of the
/// view, kept inside the view. Show it, then call [`toggle_on_title_click`].
pub fn tool_window<'a>(
    ctx: &egui::Context,
    title: &'a str,
    corner: Corner,
    open: bool,
) -> egui::Window<'a> {
    let area = tool_area(ctx);
    // The id egui derives from a title is not `Id::new(title)`: set it, so that
    // [`toggle_on_title_click`] finds the window's parts.
    egui::Window::new(title)
        .id(egui::Id::new(title))
        .default_open(open)
        .pivot(corner.align())
        .default_pos(corner.of(area))
        .constrain_to(area)
}

/// Opens or closes the window titled `title` (made by [`tool_window`]) when its title bar was
/// clicked once; egui itself wants a click on the small arrow or a double click (the arrow is not
/// part of egui's title area, so it is not toggled twice). Call after showing the window.
pub fn toggle_on_title_click(ctx: &egui::Context, title: &str, default_open: bool) {
    let id = egui::Id::new(title);
    let Some(title_bar) = ctx.read_response(id.with("__title_click")) else {
        return;
    };
    // egui may run a frame's input through more than one pass: toggle once per frame.
    let frame = ctx.cumulative_frame_nr();
    let last = id.with("clayloft title toggled");
    let again = ctx.data(|d| d.get_temp::<u64>(last)) == Some(frame);
    if title_bar.clicked() && !title_bar.double_clicked() && !again {
        ctx.data_mut(|d| d.insert_temp(last, frame));
        let mut state = egui::collapsing_header::CollapsingState::load_with_default_open(
            ctx,
            id.with("collapsing"),
            default_open,
        );
        state.set_open(!state.is_open());
        state.store(ctx);
        ctx.request_repaint();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    #[test]
    fn a_click_on_the_title_opens_and_closes_a_tool_window() {
        let mut h = Harness::builder()
            .with_size(egui::vec2(800.0, 600.0))
            .build_ui(|ui| {
                let ctx = &ui.ctx().clone();
                set_tool_area(
                    ctx,
                    egui::Rect::from_min_max(egui::pos2(300.0, 40.0), egui::pos2(780.0, 560.0)),
                );
                tool_window(ctx, "Tools", Corner::TopRight, false).show(ctx, |ui| {
                    ui.label("inside the window");
                });
                toggle_on_title_click(ctx, "Tools", false);
            });
        h.run();
        assert!(
            h.query_by_label("inside the window").is_none(),
            "starts closed"
        );
        h.get_by_label("Tools").click();
        h.run();
        assert!(
            h.query_by_label("inside the window").is_some(),
            "one click opens it"
        );
        // It stays inside the view area, in its corner.
        let rect = h.get_by_label("inside the window").rect();
        assert!(
            rect.max.x <= 780.0 && rect.min.x >= 300.0 && rect.min.y >= 40.0,
            "{rect:?}"
        );
        h.get_by_label("Tools").click();
        h.run();
        assert!(
            h.query_by_label("inside the window").is_none(),
            "another click closes it"
        );
    }
}
