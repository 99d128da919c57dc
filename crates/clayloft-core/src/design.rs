//! The design file (SPEC §6): a TOML document, version 1, that says everything needed to make a
//! vessel. Every field except `version` and the two contours has a default (the paper's clay
//! printer); unknown fields are errors so that typos never pass silently.
//!
//! This module holds the data types and their defaults only. Reading a file with line-accurate
//! errors is [`crate::load`]; checking physical ranges is [`crate::validate`].

use serde::{Deserialize, Serialize};

/// The only design-file version this build reads and writes.
pub const DESIGN_VERSION: u32 = 1;

/// A whole design: printer, shape, control lines, texture and constraint policy.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    pub version: u32,
    #[serde(default = "default_name")]
    pub name: String,
    #[serde(default)]
    pub printer: Printer,
    pub shape: Shape,
    #[serde(default)]
    pub control: Control,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<Texture>,
    #[serde(default)]
    pub constraints: Constraints,
    /// The clay body (SPEC §14): stoneware when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clay: Option<crate::clay::ClayTable>,
    /// Folder that image and SVG contour paths are relative to: the design file's (set by the
    /// loader; not part of the file, not compared).
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

impl Design {
    /// The design as it must be written to a file in folder `dir`: image and SVG contour paths,
    /// relative to [`Design::base_dir`], rewritten relative to `dir` (with `..` where needed;
    /// absolute where no relative path exists, as across Windows drives), and `base_dir` set to
    /// `dir`. Absolute paths, and a design that has no folder yet, are left as they are.
    pub fn moved_to(&self, dir: &std::path::Path) -> Design {
        let mut moved = self.clone();
        moved.base_dir = Some(dir.to_path_buf());
        let Some(from) = self.base_dir.as_deref() else {
            return moved;
        };
        let absolute = |p: &std::path::Path| std::path::absolute(p).unwrap_or(p.to_path_buf());
        let (from, to) = (absolute(from), absolute(dir));
        if from == to {
            return moved;
        }
        for spec in [&mut moved.shape.lower, &mut moved.shape.upper] {
            if let ContourSpec::Image { path, .. } | ContourSpec::Svg { path, .. } = spec {
                let file = std::path::Path::new(path.as_str());
                if file.is_absolute() {
                    continue;
                }
                let target = from.join(file);
                let rebased = pathdiff::diff_paths(&target, &to).unwrap_or(target);
                // Forward slashes keep the file portable between systems.
                *path = rebased.to_string_lossy().replace('\\', "/");
            }
        }
        if let Some(mesh) = &mut moved.shape.mesh
            && mesh.path.is_relative()
        {
            let target = from.join(&mesh.path);
            mesh.path = pathdiff::diff_paths(&target, &to).unwrap_or(target);
        }
        moved
    }
}

/// Two designs are equal when their files would say the same (the folder they came from aside).
impl PartialEq for Design {
    fn eq(&self, o: &Design) -> bool {
        self.version == o.version
            && self.name == o.name
            && self.printer == o.printer
            && self.shape == o.shape
            && self.control == o.control
            && self.texture == o.texture
            && self.constraints == o.constraints
    }
}

fn default_name() -> String {
    "untitled vessel".to_string()
}

/// How E values are written: per move (M83) or cumulative (M82).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ExtrusionMode {
    #[default]
    Relative,
    Absolute,
}

/// The shape of the bed (SPEC §12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum BedShape {
    #[default]
    Rectangle,
    /// A round bed of `bed_diameter` (deltas).
    Circle,
}

impl BedShape {
    /// As written in design and profile files (and G-code headers).
    pub fn name(self) -> &'static str {
        match self {
            BedShape::Rectangle => "rectangle",
            BedShape::Circle => "circle",
        }
    }

    /// The shape a file calls `name`.
    pub fn from_name(name: &str) -> Option<BedShape> {
        [BedShape::Rectangle, BedShape::Circle]
            .into_iter()
            .find(|b| b.name() == name)
    }

    /// True when the bed-frame point (x, y) lies on a bed of this shape, `bed_x` × `bed_y`
    /// (a round bed is `bed_x` across), within `eps`.
    pub fn contains(self, bed_x: f64, bed_y: f64, x: f64, y: f64, eps: f64) -> bool {
        match self {
            BedShape::Rectangle => x >= -eps && y >= -eps && x <= bed_x + eps && y <= bed_y + eps,
            BedShape::Circle => {
                let r = bed_x / 2.0;
                let (dx, dy) = (x - r, y - bed_y / 2.0);
                dx * dx + dy * dy <= (r + eps) * (r + eps)
            }
        }
    }
}

/// Where the printer's (0, 0) is on the bed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Origin {
    /// The front left corner (most cartesian printers).
    #[default]
    #[serde(rename = "corner")]
    Corner,
    /// The centre of the bed (deltas, some large-format printers).
    #[serde(rename = "centre", alias = "center")]
    Centre,
}

impl Origin {
    /// As written in design and profile files (and G-code headers).
    pub fn name(self) -> &'static str {
        match self {
            Origin::Corner => "corner",
            Origin::Centre => "centre",
        }
    }

    /// The origin a file calls `name` (`"center"` too, as the design files accept it).
    pub fn from_name(name: &str) -> Option<Origin> {
        match name {
            "center" => Some(Origin::Centre),
            _ => [Origin::Corner, Origin::Centre]
                .into_iter()
                .find(|o| o.name() == name),
        }
    }

    /// Where this origin lies in the bed frame of a `bed_x` × `bed_y` bed.
    pub fn offset(self, bed_x: f64, bed_y: f64) -> [f64; 2] {
        match self {
            Origin::Corner => [0.0, 0.0],
            Origin::Centre => [bed_x / 2.0, bed_y / 2.0],
        }
    }
}

/// How the printer moves its nozzle; the start/end G-code and the time estimate follow it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Kinematics {
    #[default]
    Cartesian,
    Delta,
    Scara,
}

/// The firmware's G-code dialect: the default start and end G-code follow it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Dialect {
    #[default]
    Marlin,
    Klipper,
    RepRapFirmware,
}

impl Dialect {
    /// The firmware's own name, for people (headers, lists).
    pub fn title(self) -> &'static str {
        match self {
            Dialect::Marlin => "Marlin",
            Dialect::Klipper => "Klipper",
            Dialect::RepRapFirmware => "RepRapFirmware",
        }
    }
}

impl Kinematics {
    /// As written in design and profile files.
    pub fn name(self) -> &'static str {
        match self {
            Kinematics::Cartesian => "cartesian",
            Kinematics::Delta => "delta",
            Kinematics::Scara => "scara",
        }
    }
}

impl ExtrusionMode {
    /// The G-code that puts the firmware in this mode.
    pub fn gcode(self) -> &'static str {
        match self {
            ExtrusionMode::Relative => "M83",
            ExtrusionMode::Absolute => "M82",
        }
    }
}

/// The printer and the print settings. Defaults: the paper's clay printer (Cerambot Plus class).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Printer {
    /// A printer profile (SPEC §12) these settings start from: the name of a shipped profile
    /// (`clayloft printers` lists them) or a path to a profile file, relative to the design.
    /// Fields given here override the profile's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile: Option<String>,
    /// `"rectangle"` (`bed_x` × `bed_y`) or `"circle"` (`bed_diameter`).
    pub bed_shape: BedShape,
    /// Diameter of a round bed, mm (with `bed_shape = "circle"`; then `bed_x` = `bed_y` = it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bed_diameter: Option<f64>,
    /// Where the printer's (0, 0) is: `"corner"` or `"centre"`.
    pub origin: Origin,
    pub kinematics: Kinematics,
    /// `"marlin"`, `"klipper"` or `"reprapfirmware"`: the default start/end G-code.
    pub dialect: Dialect,
    /// Acceleration of print moves, mm/s² (the time estimate plans with it).
    pub max_acceleration: f64,
    /// Cornering limit as Marlin's junction deviation, mm (Klipper's square corner velocity v
    /// is the same limit with `junction_deviation = v² (√2 − 1) / max_acceleration`).
    pub junction_deviation: f64,
    /// G-code before the path (placeholders in braces, see the README); `None` = the dialect's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_gcode: Option<String>,
    /// G-code after the path; `None` = the dialect's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_gcode: Option<String>,
    /// G-code a printer host sends when a print is cancelled, in place of the rest of the job
    /// (stop extruding, lift clear of the part, park; placeholders as in `end_gcode`); `None` =
    /// the end G-code, which does exactly that.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cancel_gcode: Option<String>,
    /// Header comments that printer hosts read (time, clay used, layers) and layer messages.
    pub host_metadata: bool,
    /// `M73` progress (percent and minutes left) through the path.
    pub progress: bool,
    /// A small picture of the vessel in the header, for host and printer screens.
    pub thumbnail: bool,
    /// Bed size along x, mm.
    pub bed_x: f64,
    /// Bed size along y, mm.
    pub bed_y: f64,
    /// Maximum build height, mm.
    pub max_z: f64,
    pub nozzle_diameter: f64,
    /// Width of the extruded bead, mm; the printed wall is this thick.
    pub line_width: f64,
    /// Nominal layer height, mm; must lie in `min_layer_height ..= max_layer_height`.
    pub layer_height: f64,
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    /// Length of the nozzle tube below its holder, mm (collision limit per layer).
    pub nozzle_length: f64,
    /// Largest lean of the wall from vertical that prints without support, degrees.
    pub max_overhang_deg: f64,
    /// mm/s.
    pub print_speed: f64,
    /// mm/s, approach and exit only.
    pub travel_speed: f64,
    /// Calibration constant of the clay extruder (ram or auger equivalent), mm.
    pub feed_diameter: f64,
    pub flow_multiplier: f64,
    pub extrusion: ExtrusionMode,
    /// Minimum time per revolution, s (0 = off): small layers are slowed so the clay can stiffen.
    pub min_layer_time: f64,
    /// Length of wall path at the start of the spiral over which flow ramps up from 25 %, mm.
    pub flow_ramp_start: f64,
    /// Length of path at the end over which flow ramps down to 25 %, mm.
    pub flow_ramp_end: f64,
}

impl Default for Printer {
    fn default() -> Self {
        Printer {
            profile: None,
            bed_shape: BedShape::Rectangle,
            bed_diameter: None,
            origin: Origin::Corner,
            kinematics: Kinematics::Cartesian,
            dialect: Dialect::Marlin,
            // A desktop clay printer's print acceleration: Eazao's own Cura definition
            // (resources/definitions/eazao_zero.def.json, acceleration_print = 300).
            max_acceleration: 300.0,
            // Marlin's default JUNCTION_DEVIATION_MM (Configuration.h).
            junction_deviation: 0.013,
            start_gcode: None,
            end_gcode: None,
            cancel_gcode: None,
            host_metadata: true,
            progress: true,
            thumbnail: true,
            bed_x: 180.0,
            bed_y: 190.0,
            max_z: 200.0,
            nozzle_diameter: 3.0,
            line_width: 3.0,
            layer_height: 1.0,
            min_layer_height: 0.25,
            max_layer_height: 1.0,
            nozzle_length: 30.0,
            max_overhang_deg: 45.0,
            print_speed: 20.0,
            travel_speed: 50.0,
            feed_diameter: 3.0,
            flow_multiplier: 1.0,
            extrusion: ExtrusionMode::Relative,
            min_layer_time: 0.0,
            flow_ramp_start: 0.0,
            flow_ramp_end: 0.0,
        }
    }
}

/// The large-scale shape: height, sampling, placement, base and the two contours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shape {
    #[serde(default = "default_height")]
    pub height: f64,
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Centre of the design on the bed, mm; `None` = bed centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 2]>,
    #[serde(default = "default_base_layers")]
    pub base_layers: usize,
    /// Beads side by side in the wall (SPEC §13), 1 ..= 3: the outer bead on the designed
    /// surface, each further bead one line width inward, all in the one spiral.
    #[serde(default = "default_walls", skip_serializing_if = "is_one_wall")]
    pub walls: usize,
    /// Weave the inner beads half a bead into the outer one and back (a zig-zag tie between the
    /// beads), with `walls` ≥ 2.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub wall_ties: bool,
    /// Contour at z = 0 (not given for a design from a mesh).
    #[serde(
        default = "ContourSpec::missing",
        skip_serializing_if = "ContourSpec::is_missing"
    )]
    pub lower: ContourSpec,
    /// Contour at z = height (not given for a design from a mesh).
    #[serde(
        default = "ContourSpec::missing",
        skip_serializing_if = "ContourSpec::is_missing"
    )]
    pub upper: ContourSpec,
    /// The shape from a mesh instead of two contours (SPEC §15): the wall follows the mesh's
    /// slices; the height comes from the mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshSource>,
}

/// A vessel mesh to slice (`[shape.mesh]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSource {
    /// The STL file, relative to the design file's folder.
    pub path: std::path::PathBuf,
    /// Scale factor applied to the mesh (1 = its numbers are millimetres; 25.4 for inches).
    #[serde(default = "default_mesh_scale")]
    pub scale: f64,
    /// Turn about the x axis before slicing, degrees (90 stands a Y-up export upright).
    #[serde(default)]
    pub rotate_x: f64,
}

fn default_mesh_scale() -> f64 {
    1.0
}

fn default_height() -> f64 {
    120.0
}
fn default_samples() -> usize {
    200
}
fn default_base_layers() -> usize {
    2
}
fn default_walls() -> usize {
    1
}
fn is_one_wall(walls: &usize) -> bool {
    *walls == 1
}

impl ContourSpec {
    /// The value of a contour the design file does not give (a design from a mesh has none):
    /// refused by the validator unless `[shape.mesh]` is there, and never written back.
    pub fn missing() -> ContourSpec {
        ContourSpec::Circle { radius: -1.0 }
    }

    /// Whether this is [`ContourSpec::missing`].
    pub fn is_missing(&self) -> bool {
        *self == ContourSpec::missing()
    }
}

/// A closed contour, by kind. Dimensions in mm, centred on the origin before alignment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ContourSpec {
    Circle {
        radius: f64,
    },
    Ellipse {
        rx: f64,
        ry: f64,
    },
    /// Regular polygon of `sides` with circumradius `radius`, corners rounded by `corner_radius`.
    Polygon {
        sides: usize,
        radius: f64,
        #[serde(default)]
        corner_radius: f64,
    },
    Star {
        points: usize,
        outer_radius: f64,
        inner_radius: f64,
    },
    /// Rose / petal curve `r(θ) = radius + amplitude·cos(petals·θ)`.
    Rose {
        radius: f64,
        amplitude: f64,
        petals: usize,
    },
    /// Closed centripetal Catmull–Rom spline through the points.
    Spline {
        points: Vec<[f64; 2]>,
    },
    /// Outline of the largest shape in a picture (PNG, JPEG, …), longer side `size` mm. `path`
    /// is relative to the design file. `threshold` (grey level 0–255) overrides Otsu's automatic
    /// one.
    Image {
        path: String,
        size: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        threshold: Option<u8>,
    },
    /// The first closed path of an SVG drawing (or the path `id`), longer side `size` mm. `path`
    /// is relative to the design file.
    Svg {
        path: String,
        size: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        id: Option<String>,
    },
}

/// Control lines: large-scale shaping of the loft.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Control {
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub vertical: Vec<VerticalLine>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub horizontal: Vec<HorizontalLine>,
}

/// Outward offset along the height: `points` are `[t, offset_mm]` with `t` the height fraction.
/// With `angle` (and `width`) it acts only around that angle, with a smooth fall-off.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerticalLine {
    pub points: Vec<[f64; 2]>,
    /// Centre angle of a local line, degrees counter-clockwise from +x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f64>,
    /// Full width of a local line's influence, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
}

/// Z offset around a section: `points` are `[angle_deg, dz_mm]`, periodic in angle; full effect
/// at height fraction `at`, fading to zero over `reach`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HorizontalLine {
    pub at: f64,
    pub reach: f64,
    pub points: Vec<[f64; 2]>,
}

/// How the x and y waves of a texture combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    #[default]
    Product,
    Sum,
}

/// Periodic waveform.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WaveKind {
    Sine,
    Triangle,
    Square,
}

/// One periodic wave: amplitude (mm) and period (samples for x, layers for y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wave {
    pub wave: WaveKind,
    pub period: f64,
    pub amplitude: f64,
}

/// Small-scale texture: periodic waves embedded along the surface normal (SPEC §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Texture {
    #[serde(default)]
    pub combine: Combine,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<Wave>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<Wave>,
    /// Shift of the x wave per layer, samples (twisted textures).
    #[serde(default)]
    pub phase_drift: f64,
    /// Height fraction where the texture starts.
    #[serde(default)]
    pub start: f64,
    /// Height fraction where the texture ends.
    #[serde(default = "one")]
    pub end: f64,
}

fn one() -> f64 {
    1.0
}

/// Whether manufacturing limits are enforced (corrected) or only reported.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Constraints {
    pub enforce: bool,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints { enforce: true }
    }
}

impl Printer {
    /// A round bed is `bed_diameter` across in x and y.
    pub fn normalize(&mut self) {
        if self.bed_shape == BedShape::Circle
            && let Some(d) = self.bed_diameter
        {
            self.bed_x = d;
            self.bed_y = d;
        }
    }

    /// Where the printer's (0, 0) lies in Clayloft's bed frame (x, y from the bed's front left
    /// corner, 0 … `bed_x`, 0 … `bed_y`): the corner, or the bed centre. G-code coordinates are
    /// bed-frame coordinates less this offset.
    pub fn origin_offset(&self) -> [f64; 2] {
        self.origin.offset(self.bed_x, self.bed_y)
    }

    /// True when the bed-frame point (x, y) lies on the bed (its real shape).
    pub fn on_bed(&self, x: f64, y: f64, eps: f64) -> bool {
        self.bed_shape.contains(self.bed_x, self.bed_y, x, y, eps)
    }
}

impl Design {
    /// Centre of the design in the bed frame: `shape.center` (given in the printer's own
    /// coordinates), or the bed centre.
    pub fn center(&self) -> [f64; 2] {
        let [ox, oy] = self.printer.origin_offset();
        match self.shape.center {
            Some([x, y]) => [x + ox, y + oy],
            None => [self.printer.bed_x / 2.0, self.printer.bed_y / 2.0],
        }
    }

    /// The design as TOML text, in the file format it was read from.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}
