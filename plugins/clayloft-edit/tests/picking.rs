//! Picking in a headless app, driven by the pointer events Bevy's picking sends (clicks, drags)
//! on the shipped default design, where at 0° the rim radius, the end of the vertical control
//! line and a point of the horizontal control line are drawn on the same spot.

use std::time::Duration;

use bevy::camera::NormalizedRenderTarget;
use bevy::picking::backend::HitData;
use bevy::picking::events::{Click, Drag, DragEnd, DragStart, Pointer};
use bevy::picking::pointer::{Location, PointerButton, PointerId};
use bevy::prelude::*;
use clayloft_edit::{DragHint, EditPlugin, Selection};
use clayloft_model::handles::{HandleRole, describe};
use clayloft_model::*;

fn app() -> App {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/designs/petal-vase.toml");
    let design = clayloft_core::load::load_design(&path)
        .expect("the default design")
        .design;
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin::default(),
        TransformPlugin,
        ModelPlugin,
        EditPlugin,
    ));
    app.init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .insert_resource(ButtonInput::<KeyCode>::default())
        .insert_resource(DesignDoc {
            design,
            path: Some(path),
        });
    app.world_mut()
        .spawn((Camera3d::default(), Transform::from_xyz(0.0, 200.0, 400.0)));
    for _ in 0..4 {
        app.update();
    }
    app
}

fn camera(app: &mut App) -> Entity {
    app.world_mut()
        .query_filtered::<Entity, With<Camera3d>>()
        .single(app.world())
        .unwrap()
}

fn location() -> Location {
    Location {
        target: NormalizedRenderTarget::None {
            width: 1280,
            height: 720,
        },
        position: Vec2::new(640.0, 360.0),
    }
}

/// The entity of the handle of `role`.
fn handle(app: &mut App, role: HandleRole) -> Entity {
    app.world_mut()
        .query::<(Entity, &EditHandle)>()
        .iter(app.world())
        .find(|(_, h)| h.0 == role)
        .map(|(e, _)| e)
        .unwrap_or_else(|| panic!("no handle {role:?}"))
}

/// Sends the mouse's pointer event `event` to `entity`, as Bevy's picking would, and runs a frame.
fn send<E>(app: &mut App, entity: Entity, event: E)
where
    E: std::fmt::Debug + Clone + Reflect,
    for<'a> Pointer<E>: Event<Trigger<'a>: Default>,
{
    app.world_mut()
        .trigger(Pointer::new(PointerId::Mouse, location(), event, entity));
    app.update();
}

fn click(app: &mut App, entity: Entity) {
    let hit = HitData::new(camera(app), 1.0, None, None);
    let click = Click {
        button: PointerButton::Primary,
        hit,
        duration: Duration::from_millis(90),
        count: 1,
    };
    send(app, entity, click);
}

fn selected(app: &App) -> Option<HandleRole> {
    app.world().resource::<Selection>().0
}

fn hint(app: &App) -> String {
    app.world()
        .resource::<DragHint>()
        .0
        .clone()
        .unwrap_or_default()
}

#[test]
fn clicking_a_stack_of_handles_picks_each_in_turn_and_says_which() {
    let mut app = app();
    let design = app.world().resource::<DesignDoc>().design.clone();
    let rim = handle_role(&design, "rim rose radius (at 0°)");
    let entity = handle(&mut app, rim);
    click(&mut app, entity);
    assert_eq!(selected(&app), Some(rim));
    let first = hint(&app);
    assert!(
        first.starts_with("rim rose radius (at 0°) (1 of 3 handles here"),
        "{first}"
    );
    // Clicking the same spot again picks the next handle there, then the next, then round.
    let mut seen = vec![rim];
    for _ in 0..3 {
        click(&mut app, entity);
        seen.push(selected(&app).unwrap());
    }
    let words: Vec<String> = seen.iter().map(|r| describe(*r, &design)).collect();
    assert_eq!(
        words,
        [
            "rim rose radius (at 0°)",
            "vertical control line 1, point 3: offset (in and out); an end point stays at the line's end",
            "horizontal control line 1, point 1: up and down",
            "rim rose radius (at 0°)",
        ]
    );
    assert!(hint(&app).contains("click again for the next"));
    // A handle on its own is simply picked.
    let belly = handle_role(
        &design,
        "vertical control line 1, point 2: height and offset",
    );
    let lone = handle(&mut app, belly);
    click(&mut app, lone);
    assert_eq!(selected(&app), Some(belly));
    assert_eq!(hint(&app), describe(belly, &design));
}

#[test]
fn a_drag_starting_on_a_stack_moves_the_handle_picked_there() {
    let mut app = app();
    let design = app.world().resource::<DesignDoc>().design.clone();
    let rim = handle_role(&design, "rim rose radius (at 0°)");
    let entity = handle(&mut app, rim);
    // Pick the second handle of the stack, then press on the stack and drag.
    click(&mut app, entity);
    click(&mut app, entity);
    let picked = selected(&app).unwrap();
    assert_ne!(picked, rim);
    let hit = HitData::new(camera(&mut app), 1.0, None, None);
    send(
        &mut app,
        entity,
        DragStart {
            button: PointerButton::Primary,
            hit,
        },
    );
    let drag = app.world().resource::<clayloft_edit::ActiveDrag>().0;
    assert_eq!(
        drag.map(|d| d.role),
        Some(picked),
        "the picked handle is dragged"
    );
    // A press that moved a little is still a click: it picks from the stack as before.
    send(
        &mut app,
        entity,
        Drag {
            button: PointerButton::Primary,
            distance: Vec2::new(2.0, 0.0),
            delta: Vec2::new(2.0, 0.0),
        },
    );
    click(&mut app, entity);
    let after = selected(&app).unwrap();
    assert_ne!(after, picked, "the click moved on to the next handle");
    send(
        &mut app,
        entity,
        DragEnd {
            button: PointerButton::Primary,
            distance: Vec2::new(2.0, 0.0),
        },
    );
    assert!(
        app.world()
            .resource::<clayloft_edit::ActiveDrag>()
            .0
            .is_none()
    );
}

#[test]
fn a_drag_across_a_locked_direction_says_why() {
    let app = app();
    let design = app.world().resource::<DesignDoc>().design.clone();
    let point = handle_role(&design, "horizontal control line 1, point 2: up and down");
    assert_eq!(
        clayloft_edit::drag::locked_hint(point, &design),
        "horizontal control line 1, point 2: up and down — a horizontal control line's point moves only up and down: its angle around the vessel is set in the panel"
    );
}

/// The role whose description is `words`.
fn handle_role(design: &clayloft_core::Design, words: &str) -> HandleRole {
    clayloft_model::handles::handle_roles(design)
        .into_iter()
        .find(|r| describe(*r, design) == words)
        .unwrap_or_else(|| {
            let all: Vec<String> = clayloft_model::handles::handle_roles(design)
                .iter()
                .map(|r| describe(*r, design))
                .collect();
            panic!("no handle \"{words}\" among {all:?}")
        })
}
