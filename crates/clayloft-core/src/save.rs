//! Saving a design over its own file (SPEC §6): the file's text is edited in place rather than
//! written anew, so that the potter's comments, the order of the keys and the way numbers were
//! written survive a save from the app.
//!
//! The new design is written as TOML ([`Design::to_toml`]) and merged into the old document with
//! `toml_edit`: a value the edit changed replaces the old one (keeping the comment beside it), a
//! value it did not change is left exactly as it was written, a key the old file did not have is
//! added only when its value differs from what the old file already meant (its default, or its
//! printer profile's), and a key whose value the edit cleared is removed.

use toml_edit::{DocumentMut, Item, Table};

use crate::design::Design;

/// The text of `design` written over `previous` (the file's current text), keeping its
/// comments and layout. `meant` is the design `previous` loads as (profile and defaults
/// applied); without it, or when `previous` is no TOML document, the design is written anew.
pub fn toml_keeping(design: &Design, previous: &str, meant: Option<&Design>) -> String {
    let fresh = design.to_toml();
    let (Ok(mut old), Ok(new), Some(meant)) = (
        previous.parse::<DocumentMut>(),
        fresh.parse::<DocumentMut>(),
        meant,
    ) else {
        return fresh;
    };
    let Ok(was) = meant.to_toml().parse::<DocumentMut>() else {
        return fresh;
    };
    merge(old.as_table_mut(), new.as_table(), Some(was.as_table()));
    old.to_string()
}

/// Merges `new` into `old` (see the module documentation); `was` is what `old` meant.
fn merge(old: &mut Table, new: &Table, was: Option<&Table>) {
    let gone: Vec<String> = old
        .iter()
        .map(|(k, _)| k.to_string())
        .filter(|k| !new.contains_key(k))
        .collect();
    for key in gone {
        old.remove(&key);
    }
    for (key, item) in new.iter() {
        let before = was.and_then(|t| t.get(key));
        match old.get_mut(key) {
            Some(existing) => merge_item(existing, item, before),
            None => match (item, before) {
                // A table the old file did not have: only the keys whose meaning changed.
                (Item::Table(n), Some(Item::Table(b))) => {
                    let mut added = Table::new();
                    merge(&mut added, n, Some(b));
                    if !added.is_empty() {
                        old.insert(key, Item::Table(added));
                    }
                }
                // Not written in the old file: only if the edit changed what it meant.
                _ => {
                    if before.is_none_or(|b| !same(b, item)) {
                        old.insert(key, item.clone());
                    }
                }
            },
        }
    }
}

/// Merges one item (see [`merge`]).
fn merge_item(old: &mut Item, new: &Item, was: Option<&Item>) {
    if same(old, new) {
        return;
    }
    match (old, new) {
        (Item::Table(o), Item::Table(n)) => merge(o, n, was.and_then(Item::as_table)),
        (Item::ArrayOfTables(o), Item::ArrayOfTables(n)) if o.len() == n.len() => {
            let was = was.and_then(Item::as_array_of_tables);
            for (k, (ot, nt)) in o.iter_mut().zip(n.iter()).enumerate() {
                merge(ot, nt, was.and_then(|w| w.get(k)));
            }
        }
        (Item::Value(o), Item::Value(n)) => {
            let decor = o.decor().clone();
            *o = n.clone();
            *o.decor_mut() = decor;
        }
        (o, n) => *o = n.clone(),
    }
}

/// Whether two items hold the same data, however they are written (`60` and `60.0` for a
/// number field are the same; comments and spacing do not count).
fn same(a: &Item, b: &Item) -> bool {
    let text = |i: &Item| -> Option<String> {
        let mut doc = DocumentMut::new();
        doc.insert("v", i.clone());
        let parsed: toml::Value = toml::from_str(&doc.to_string()).ok()?;
        Some(normalised(parsed.get("v")?).to_string())
    };
    match (text(a), text(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// A TOML value with integers written as floats, so that `60` and `60.0` compare equal.
fn normalised(v: &toml::Value) -> toml::Value {
    match v {
        toml::Value::Integer(i) => toml::Value::Float(*i as f64),
        toml::Value::Array(a) => toml::Value::Array(a.iter().map(normalised).collect()),
        toml::Value::Table(t) => {
            toml::Value::Table(t.iter().map(|(k, v)| (k.clone(), normalised(v))).collect())
        }
        other => other.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::load_design_text;
    use std::path::{Path, PathBuf};

    fn shipped() -> Vec<PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/designs");
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        v.sort();
        v
    }

    /// Comment text of a file: every `# …` from each line, in order.
    fn comments(text: &str) -> Vec<String> {
        text.lines()
            .filter_map(|l| l.find('#').map(|i| l[i..].trim().to_string()))
            .collect()
    }

    #[test]
    fn saving_after_edits_keeps_every_comment_and_loads_back_as_edited() {
        for path in shipped() {
            let text = std::fs::read_to_string(&path).unwrap();
            let meant = load_design_text(&path, text.clone()).unwrap().design;
            let mut edited = meant.clone();
            edited.shape.height += 7.0;
            edited.printer.print_speed += 1.5;
            edited.name = format!("{} (edited)", edited.name);
            edited.texture = None;
            let saved = toml_keeping(&edited, &text, Some(&meant));
            let back = load_design_text(&path, saved.clone()).unwrap().design;
            assert_eq!(back, edited, "{}", path.display());
            // Every comment survives, in order (the texture table and its comments go with it).
            let kept = comments(&saved);
            let mut it = kept.iter();
            let had_texture = text.contains("[texture");
            for c in comments(&text) {
                if had_texture && !kept.contains(&c) {
                    continue;
                }
                assert!(
                    it.any(|k| *k == c),
                    "{}: lost comment {c:?}",
                    path.display()
                );
            }
            // Only the edited printer field is added, not every field of the printer.
            let added: Vec<&str> = saved
                .lines()
                .filter(|l| !text.lines().any(|o| o == *l))
                .collect();
            assert!(added.len() <= 5, "{}: added {added:?}", path.display());
        }
    }

    #[test]
    fn an_unedited_design_saves_to_the_same_text() {
        for path in shipped() {
            let text = std::fs::read_to_string(&path).unwrap();
            let meant = load_design_text(&path, text.clone()).unwrap().design;
            assert_eq!(
                toml_keeping(&meant, &text, Some(&meant)),
                text,
                "{}",
                path.display()
            );
        }
    }

    #[test]
    fn a_file_that_is_no_toml_is_written_anew() {
        let meant = crate::load::parse_design(
            "version = 1\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n",
        )
        .unwrap();
        assert_eq!(
            toml_keeping(&meant, "not [toml", Some(&meant)),
            meant.to_toml()
        );
    }
}
