//! Every character the editor's plugins put on screen has a glyph in egui's fonts: a missing one
//! renders as an empty box (the Undo/Redo arrows did). The text shown comes from the plugins'
//! string literals; comments are skipped.

use std::path::Path;

use bevy_egui::egui;

/// The non-ASCII characters in the string literals of the Rust files under `dir`, with the
/// file each was first seen in.
fn shown_characters(dir: &Path, out: &mut Vec<(char, String)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            shown_characters(&path, out);
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for line in text.lines() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            // Inside double quotes only (string literals).
            let mut inside = false;
            for c in code.chars() {
                if c == '"' {
                    inside = !inside;
                } else if inside && !c.is_ascii() && !out.iter().any(|(k, _)| *k == c) {
                    out.push((c, path.display().to_string()));
                }
            }
        }
    }
}

#[test]
fn every_character_the_editor_shows_has_a_glyph() {
    let plugins = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut chars = Vec::new();
    for plugin in std::fs::read_dir(&plugins).unwrap() {
        let src = plugin.unwrap().path().join("src");
        if src.is_dir() {
            shown_characters(&src, &mut chars);
        }
    }
    assert!(
        chars.iter().any(|(c, _)| *c == '°'),
        "the scan finds the editor's text"
    );
    let ctx = egui::Context::default();
    let _ = ctx.run_ui(Default::default(), |_| {});
    let font = egui::FontId::proportional(14.0);
    let missing: Vec<String> = chars
        .iter()
        .filter(|(c, _)| !ctx.fonts_mut(|f| f.has_glyph(&font, *c)))
        .map(|(c, file)| format!("{c:?} (U+{:04X}) in {file}", *c as u32))
        .collect();
    assert!(missing.is_empty(), "no glyph for: {missing:#?}");
}
