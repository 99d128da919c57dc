//! Reading a design file: bytes → TOML → [`Design`] → validated, with every problem reported as
//! one sentence that names the file, the line and the field.

use std::path::{Path, PathBuf};

use crate::design::Design;
use crate::validate::{FieldError, validate};

/// Largest design file we read, bytes. Designs are a few kilobytes; this keeps a wrong path (a
/// video, a disk image) from being read into memory.
const MAX_DESIGN_BYTES: u64 = 16 * 1024 * 1024;

/// A problem reading a design file, ready to show to the user as one line.
#[derive(Debug, Clone, thiserror::Error)]
pub enum DesignError {
    #[error("{file}: cannot read the design: {reason}")]
    Read { file: String, reason: String },
    #[error("{file}:{line}: {message}")]
    Syntax {
        file: String,
        line: usize,
        message: String,
    },
    #[error("{file}{}: {field}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Field {
        file: String,
        line: Option<usize>,
        field: String,
        message: String,
    },
    /// A mesh opened on its own (`clayloft gcode vase.stl`): what is wrong with it or its print.
    #[error("{file}: {message}")]
    Mesh { file: String, message: String },
}

/// A parsed and validated design together with its source text, kept so that later problems
/// (for example a shape that does not fit the bed) can still be reported with a line number.
#[derive(Debug, Clone)]
pub struct LoadedDesign {
    pub design: Design,
    pub path: PathBuf,
    source: String,
}

impl LoadedDesign {
    /// Turns a field problem found after loading into a located error for this file.
    pub fn locate(&self, err: FieldError) -> DesignError {
        if is_mesh_file(&self.path) {
            return mesh_error(&self.path, err);
        }
        located(&self.path, &self.source, err)
    }
}

/// Whether `path` names a mesh (an STL or OBJ file), which opens as a design of its own.
pub fn is_mesh_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stl") || e.eq_ignore_ascii_case("obj"))
}

/// A problem of a mesh opened on its own: the mesh's own ones without the repeated path, the
/// others (a vessel too large for the bed) with their field.
fn mesh_error(path: &Path, err: FieldError) -> DesignError {
    let file = path.display().to_string();
    let message = match err.message.strip_prefix(&format!("{file}: ")) {
        Some(own) => own.to_string(),
        None => format!("{}: {}", err.field, err.message),
    };
    DesignError::Mesh { file, message }
}

/// The design of a mesh file opened on its own: its shape from the mesh, everything else the
/// defaults (the paper's printer) or printer profile `printer`.
fn mesh_as_design(path: &Path, printer: Option<&str>) -> Result<LoadedDesign, DesignError> {
    let mut doc = toml_edit::DocumentMut::new();
    doc["version"] = toml_edit::value(i64::from(crate::design::DESIGN_VERSION));
    let stem = path.file_stem().map(|s| s.to_string_lossy().to_string());
    doc["name"] = toml_edit::value(stem.unwrap_or_else(|| "mesh".into()));
    let mut mesh = toml_edit::Table::new();
    let file_name = path.file_name().map(|s| s.to_string_lossy().to_string());
    mesh["path"] = toml_edit::value(file_name.unwrap_or_default());
    let mut shape = toml_edit::Table::new();
    shape.set_implicit(true);
    shape.insert("mesh", toml_edit::Item::Table(mesh));
    doc.insert("shape", toml_edit::Item::Table(shape));
    load_design_text_using(path, doc.to_string(), printer).map_err(|e| match e {
        DesignError::Field { field, message, .. } => {
            mesh_error(path, FieldError::new(field, message))
        }
        other => other,
    })
}

/// Reads, parses and validates a design file (with the printer profile it names, if any).
pub fn load_design(path: &Path) -> Result<LoadedDesign, DesignError> {
    load_design_using(path, None)
}

/// As [`load_design`], with printer profile `printer` (a shipped name or a profile file) in
/// place of the one the design names (`clayloft gcode --printer`).
pub fn load_design_using(path: &Path, printer: Option<&str>) -> Result<LoadedDesign, DesignError> {
    if is_mesh_file(path) {
        return mesh_as_design(path, printer);
    }
    let file = path.display().to_string();
    let read_err = |reason: String| DesignError::Read {
        file: file.clone(),
        reason,
    };
    let meta = std::fs::metadata(path).map_err(|e| read_err(io_reason(&e)))?;
    if meta.is_dir() {
        return Err(read_err("it is a folder, not a file".into()));
    }
    if meta.len() > MAX_DESIGN_BYTES {
        return Err(read_err(format!(
            "{} bytes is far too large for a design file",
            meta.len()
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| read_err(io_reason(&e)))?;
    let source = String::from_utf8(bytes)
        .map_err(|_| read_err("it is not a text (UTF-8) file — is it a design?".into()))?;
    load_design_text_using(path, source, printer)
}

/// Parses and validates the text of the design file `path` (already read); errors are located
/// in that text as [`load_design`]'s are.
pub fn load_design_text(path: &Path, source: String) -> Result<LoadedDesign, DesignError> {
    load_design_text_using(path, source, None)
}

/// As [`load_design_text`], with printer profile `printer` in place of the design's own pick.
pub fn load_design_text_using(
    path: &Path,
    source: String,
    printer: Option<&str>,
) -> Result<LoadedDesign, DesignError> {
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut design = resolve(&source, Some(&base_dir), printer).map_err(|e| e.at(path, &source))?;
    design.base_dir = Some(base_dir);
    Ok(LoadedDesign {
        design,
        path: path.to_path_buf(),
        source,
    })
}

/// A design-text problem, or one in the printer profile it names (with that file's name).
enum ResolveError {
    Design(ParseError),
    Profile(DesignError),
}

impl ResolveError {
    fn at(self, path: &Path, source: &str) -> DesignError {
        match self {
            ResolveError::Design(ParseError::Syntax { line, message }) => DesignError::Syntax {
                file: path.display().to_string(),
                line,
                message,
            },
            ResolveError::Design(ParseError::Field(f)) => located(path, source, f),
            ResolveError::Profile(e) => e,
        }
    }
}

/// Where in `source` a TOML error is (1-based line) and its message's first line.
fn syntax_at(source: &str, e: &toml::de::Error) -> (usize, String) {
    let line = e.span().map(|s| line_of(source, s.start)).unwrap_or(1);
    (line, first_line(e.message()))
}

fn syntax(source: &str, e: toml::de::Error) -> ParseError {
    let (line, message) = syntax_at(source, &e);
    ParseError::Syntax { line, message }
}

/// Design text → a validated design: the text alone (syntax, types, unknown fields), then the
/// printer profile it names (checked alone, located in its own file), the design's own
/// `[printer]` fields over the profile's, and the whole validated. A field error on a printer
/// field the design does not set itself is reported in the profile's file.
fn resolve(
    source: &str,
    base_dir: Option<&Path>,
    printer: Option<&str>,
) -> Result<Design, ResolveError> {
    let design: Design =
        toml::from_str(source).map_err(|e| ResolveError::Design(syntax(source, e)))?;
    let profile_name = printer
        .map(str::to_string)
        .or(design.printer.profile.clone());
    let Some(name) = profile_name else {
        let mut design = design;
        design.printer.normalize();
        validate(&design).map_err(|e| ResolveError::Design(ParseError::Field(e)))?;
        return Ok(design);
    };
    let found = crate::profile::find(&name, base_dir).map_err(|e| {
        ResolveError::Design(ParseError::Field(FieldError::new(
            "printer.profile",
            e.to_string(),
        )))
    })?;
    let profile_file = found.file.display().to_string();
    let profile_syntax = |e: toml::de::Error| {
        let (line, message) = syntax_at(&found.text, &e);
        ResolveError::Profile(DesignError::Syntax {
            file: profile_file.clone(),
            line,
            message,
        })
    };
    let profile: crate::profile::ProfileFile =
        toml::from_str(&found.text).map_err(profile_syntax)?;
    let mut alone = profile.printer.clone();
    alone.normalize();
    crate::validate::validate_printer(&alone)
        .map_err(|e| ResolveError::Profile(located(&found.file, &found.text, e)))?;
    // The design's own [printer] fields over the profile's.
    let design_table: toml::Table =
        toml::from_str(source).map_err(|e| ResolveError::Design(syntax(source, e)))?;
    let profile_table: toml::Table = toml::from_str(&found.text).map_err(profile_syntax)?;
    let mut merged_printer = profile_table
        .get("printer")
        .and_then(|v| v.as_table())
        .cloned()
        .unwrap_or_default();
    let own = design_table
        .get("printer")
        .and_then(|v| v.as_table())
        .cloned()
        .unwrap_or_default();
    for (k, v) in &own {
        merged_printer.insert(k.clone(), v.clone());
    }
    merged_printer.insert("profile".into(), toml::Value::String(name.clone()));
    let mut merged = design_table;
    merged.insert("printer".into(), toml::Value::Table(merged_printer));
    let mut design: Design =
        toml::Value::Table(merged)
            .try_into()
            .map_err(|e: toml::de::Error| {
                ResolveError::Design(ParseError::Syntax {
                    line: 1,
                    message: format!("with printer profile {name}: {}", first_line(e.message())),
                })
            })?;
    design.printer.normalize();
    validate(&design).map_err(|e| {
        let key = e
            .field
            .strip_prefix("printer.")
            .map(|k| k.split(['.', '[']).next().unwrap_or(k));
        match key {
            Some(k)
                if !own.contains_key(k)
                    && profile_table
                        .get("printer")
                        .and_then(|v| v.as_table())
                        .is_some_and(|t| t.contains_key(k)) =>
            {
                ResolveError::Profile(located(&found.file, &found.text, e))
            }
            _ => ResolveError::Design(ParseError::Field(e)),
        }
    })?;
    Ok(design)
}

/// A problem in design text, before a file name is attached.
#[derive(Debug, Clone, PartialEq)]
pub enum ParseError {
    Syntax { line: usize, message: String },
    Field(FieldError),
}

/// Parses and validates design text (a printer profile it names must be a shipped one: there is
/// no folder to find a profile file in).
pub fn parse_design(source: &str) -> Result<Design, ParseError> {
    resolve(source, None, None).map_err(|e| match e {
        ResolveError::Design(p) => p,
        ResolveError::Profile(d) => ParseError::Syntax {
            line: 1,
            message: d.to_string(),
        },
    })
}

fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or("").trim().to_string()
}

/// 1-based line number of byte offset `pos`.
fn line_of(source: &str, pos: usize) -> usize {
    source.as_bytes()[..pos.min(source.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

fn located(path: &Path, source: &str, err: FieldError) -> DesignError {
    DesignError::Field {
        file: path.display().to_string(),
        line: field_offset(source, &err.field).map(|o| line_of(source, o)),
        field: err.field,
        message: err.message,
    }
}

/// Byte offset in `source` of the field at a dotted path like `control.vertical[1].points[2]`.
/// Falls back to the nearest enclosing table that is written in the file.
fn field_offset(source: &str, field: &str) -> Option<usize> {
    let doc = toml_edit::Document::parse(source).ok()?;
    let mut item = doc.as_item();
    let mut best = None;
    for part in field.split('.') {
        let (key, indices) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        let next = match item {
            toml_edit::Item::Table(t) => {
                let (k, v) = t.get_key_value(key)?;
                best = k.span().map(|s| s.start).or(best);
                v
            }
            toml_edit::Item::Value(toml_edit::Value::InlineTable(t)) => {
                let (k, v) = t.get_key_value(key)?;
                best = k.span().map(|s| s.start).or(best);
                v
            }
            _ => return best,
        };
        item = next;
        if let Some(idx) = indices
            .split(['[', ']'])
            .filter(|s| !s.is_empty())
            .find_map(|s| s.parse::<usize>().ok())
        {
            match item {
                toml_edit::Item::ArrayOfTables(a) => {
                    let t = a.get(idx)?;
                    best = t.span().map(|s| s.start).or(best);
                    return descend_table(t, field, part, best);
                }
                toml_edit::Item::Value(toml_edit::Value::Array(a)) => {
                    let v = a.get(idx)?;
                    return v.span().map(|s| s.start).or(best);
                }
                _ => return best,
            }
        }
    }
    best
}

/// Continues [`field_offset`] inside one table of an array of tables.
fn descend_table(
    t: &toml_edit::Table,
    field: &str,
    part: &str,
    best: Option<usize>,
) -> Option<usize> {
    let rest = field
        .split_once(part)
        .map(|(_, r)| r.trim_start_matches('.'))
        .unwrap_or("");
    if rest.is_empty() {
        return best;
    }
    let (key, idx) = match rest.split_once('[') {
        Some((k, i)) => (
            k.split('.').next().unwrap_or(k),
            i.trim_end_matches(']').parse::<usize>().ok(),
        ),
        None => (rest.split('.').next().unwrap_or(rest), None),
    };
    let Some((k, v)) = t.get_key_value(key) else {
        return best;
    };
    let here = k.span().map(|s| s.start).or(best);
    match (v, idx) {
        (toml_edit::Item::Value(toml_edit::Value::Array(a)), Some(i)) => {
            a.get(i).and_then(|v| v.span()).map(|s| s.start).or(here)
        }
        _ => here,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = "version = 1\n[shape.lower]\ntype = \"circle\"\nradius = 40.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n";

    fn err_of(src: &str) -> ParseError {
        parse_design(src).expect_err("should fail")
    }

    #[test]
    fn minimal_design_takes_every_default() {
        let d = parse_design(MINIMAL).unwrap();
        assert_eq!(d.printer, crate::design::Printer::default());
        assert_eq!(d.shape.height, 120.0);
        assert_eq!(d.shape.samples, 200);
        assert_eq!(d.shape.base_layers, 2);
        assert_eq!(d.center(), [90.0, 95.0]);
        assert!(d.constraints.enforce);
        assert_eq!(d.name, "untitled vessel");
    }

    #[test]
    fn misspelt_field_is_named_with_its_line() {
        let src = MINIMAL.replace("[shape.upper]", "[shape]\nheigth = 3\n[shape.upper]");
        match err_of(&src) {
            ParseError::Syntax { line, message } => {
                assert!(message.contains("heigth"), "{message}");
                assert_eq!(line, 6);
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn negative_height_is_a_field_error_on_its_line() {
        let src = "version = 1\n[shape]\nheight = -5.0\n[shape.lower]\ntype = \"circle\"\nradius = 40.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n";
        let e = load_str(src);
        let msg = e.to_string();
        assert!(msg.contains(":3: shape.height"), "{msg}");
        assert!(msg.contains("greater than 0"), "{msg}");
    }

    #[test]
    fn nan_and_infinity_are_rejected() {
        for v in ["nan", "inf", "-inf"] {
            let src = MINIMAL.replace("radius = 40.0", &format!("radius = {v}"));
            match err_of(&src) {
                ParseError::Field(f) => assert_eq!(f.field, "shape.lower.radius"),
                e => panic!("{e:?}"),
            }
        }
    }

    #[test]
    fn layer_height_outside_printer_range() {
        let src = format!("{MINIMAL}[printer]\nlayer_height = 1.5\n");
        let e = load_str(&src).to_string();
        assert!(e.contains(":9: printer.layer_height"), "{e}");
        assert!(e.contains("outside the printer's range"), "{e}");
    }

    #[test]
    fn samples_bounds() {
        for s in ["2", "100000000"] {
            let src = MINIMAL.replace(
                "version = 1\n",
                &format!("version = 1\n[shape]\nsamples = {s}\n"),
            );
            match err_of(&src) {
                ParseError::Field(f) => assert_eq!(f.field, "shape.samples"),
                e => panic!("{e:?}"),
            }
        }
    }

    #[test]
    fn image_contour_size_is_checked_and_its_folder_remembered() {
        let src = MINIMAL.replace(
            "type = \"circle\"\nradius = 40.0",
            "type = \"image\"\npath = \"leaf.png\"\nsize = -80.0",
        );
        let e = load_str(&src).to_string();
        assert!(e.contains("shape.lower.size") && e.contains("-80"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.toml");
        std::fs::write(&path, MINIMAL).unwrap();
        let loaded = load_design(&path).unwrap();
        assert_eq!(loaded.design.base_dir.as_deref(), Some(dir.path()));
    }

    #[test]
    fn a_design_moved_to_another_folder_still_finds_its_pictures() {
        use crate::design::ContourSpec;
        let root = tempfile::tempdir().unwrap();
        let leaf =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/contours/leaf.png");
        std::fs::create_dir_all(root.path().join("a/pictures")).unwrap();
        std::fs::create_dir_all(root.path().join("b/deep")).unwrap();
        std::fs::copy(&leaf, root.path().join("a/pictures/leaf.png")).unwrap();
        let src = MINIMAL.replace(
            "type = \"circle\"\nradius = 40.0",
            "type = \"image\"\npath = \"pictures/leaf.png\"\nsize = 80.0",
        );
        let first = root.path().join("a/d.toml");
        std::fs::write(&first, &src).unwrap();
        let design = load_design(&first).unwrap().design;
        // Save-as in another folder: the path now leads from there to the same picture.
        let to = root.path().join("b/deep");
        let moved = design.moved_to(&to);
        let ContourSpec::Image { path, .. } = &moved.shape.lower else {
            panic!("{:?}", moved.shape.lower)
        };
        assert_eq!(path, "../../a/pictures/leaf.png");
        let second = to.join("d.toml");
        std::fs::write(&second, moved.to_toml()).unwrap();
        let reopened = load_design(&second).unwrap().design;
        assert_eq!(reopened, moved);
        let (a, b) = (crate::run(&design).unwrap(), crate::run(&reopened).unwrap());
        assert_eq!(
            a.toolpath.points, b.toolpath.points,
            "the same outline, traced again"
        );
        // The same folder, absolute paths and designs without a folder stay as they are.
        assert_eq!(design.moved_to(&root.path().join("a")), design);
        let mut loose = design.clone();
        loose.base_dir = None;
        assert_eq!(loose.moved_to(&to), loose);
    }

    #[test]
    fn array_element_field_is_located() {
        let src = format!(
            "{MINIMAL}[[control.vertical]]\npoints = [[0.0, 0.0], [1.0, 1.0]]\n[[control.vertical]]\npoints = [\n  [0.0, 0.0],\n  [1.5, 2.0],\n]\n"
        );
        let e = load_str(&src).to_string();
        assert!(e.contains(":13: control.vertical[1].points[1]"), "{e}");
    }

    #[test]
    fn wrong_version() {
        let e = load_str(&MINIMAL.replace("version = 1", "version = 7")).to_string();
        assert!(e.contains(":1: version"), "{e}");
    }

    fn load_str(src: &str) -> DesignError {
        match parse_design(src) {
            Ok(_) => panic!("should fail"),
            Err(ParseError::Field(f)) => located(Path::new("t.toml"), src, f),
            Err(ParseError::Syntax { line, message }) => DesignError::Syntax {
                file: "t.toml".into(),
                line,
                message,
            },
        }
    }
}
