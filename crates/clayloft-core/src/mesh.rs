//! Vessels from meshes (SPEC §15): a closed triangle mesh (STL, ASCII or binary, or Wavefront
//! OBJ) sliced at the layer heights, each slice's outer outline becoming that layer's section.
//!
//! - [`parse_stl`] reads the file ([`stl_io`], which merges equal vertices) after checking that a
//!   binary file is as long as its header says and not absurdly large; [`parse_obj`] reads OBJ
//!   ([`tobj`]);
//! - [`check_closed_body`] refuses what cannot be a vessel: open edges, edges of more than two
//!   triangles, several bodies, too many triangles without area;
//! - [`place`] scales, turns about x (Z-up and Y-up exports) and stands the mesh on the bed;
//! - [`slice_outlines`] cuts it at each height: every triangle that straddles the plane gives one
//!   segment between two of its edges, and segments chain through the edges they share into
//!   closed outlines. Outlines inside the outer one (a hollow vessel's inner wall) are left out;
//!   a second outline beside it (a handle, a second vessel) cannot be one spiral and is refused;
//! - [`wall_sections`] moves each outline inward by half a line width exactly (so that the
//!   printed bead's outside lies on the model's surface), samples it at equal arc length and
//!   turns each section to the start that twists least against the one below.
//!
//! A vertex exactly on a slicing plane counts as above it, so every straddling triangle crosses
//! the plane on exactly two edges and the chaining never meets a vertex.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use foldhash::fast::FixedState;
use glam::{DVec2, DVec3};

use crate::design::MeshSource;
use crate::geometry::{contains_point, dedup_closed, resample_closed, signed_area};
use crate::sample::min_twist_offset;
use crate::section::Section;
use crate::stl::Mesh;
use crate::validate::FieldError;

/// Most triangles a vessel mesh may have: ten times the 2-million-triangle meshes of a fine
/// scan, a few GB of working memory; beyond it a file is refused before it is read.
pub const MAX_TRIANGLES: usize = 20_000_000;
/// Triangles without area an exporter may leave (slivers at seams): up to 1 % are ignored.
pub const MAX_DEGENERATE_SHARE: f64 = 0.01;
/// A triangle whose area is below this is degenerate, mm².
const DEGENERATE_AREA: f64 = 1e-9;
/// The fewest bytes an ASCII STL facet takes (`facet normal 0 0 0`, `outer loop`, three
/// `vertex` lines, `endloop`, `endfacet`).
const ASCII_FACET_BYTES: usize = 100;
/// Outlines smaller than this beside the outer one are slicing noise, not a second body, mm².
const NOISE_AREA: f64 = 1.0;

/// What is wrong with a mesh, in words for the one-line message that names the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The file cannot be read as a mesh (the message says which format and why).
    #[error("{0}")]
    Read(String),
    #[error(
        "truncated: the header announces {declared} triangles ({need} bytes), the file has {got} bytes"
    )]
    Truncated { declared: u64, need: u64, got: u64 },
    #[error("{0} triangles: more than the {MAX_TRIANGLES} a vessel mesh may have")]
    TooLarge(u64),
    #[error("no triangles")]
    Empty,
    #[error(
        "not closed: {open} edges belong to one triangle only (one near x = {:.1}, y = {:.1}, z = {:.1} mm): a vessel mesh must be watertight",
        at[0], at[1], at[2]
    )]
    NotClosed { open: usize, at: [f64; 3] },
    #[error(
        "not a simple surface: {0} edges are shared by more than two triangles (touching bodies or doubled faces)"
    )]
    NonManifold(usize),
    #[error("{0} separate bodies: a vessel mesh is one closed body")]
    SeveralBodies(usize),
    #[error("{bad} of {total} triangles have no area (more than 1 %): the mesh is broken")]
    Degenerate { bad: usize, total: usize },
    #[error(
        "the slice at z = {z:.2} mm has {outlines} separate outlines (a handle, or a second vessel beside the first): one spiral can follow only one"
    )]
    SeveralOutlines { z: f64, outlines: usize },
    #[error("the slice at z = {z:.2} mm is empty: the mesh does not reach that height")]
    EmptySlice { z: f64 },
    #[error(
        "at z = {z:.2} mm the vessel is narrower than a bead ({width} mm): nothing of it is left half a bead inside its surface"
    )]
    NarrowerThanABead { z: f64, width: f64 },
}

/// Reads an STL file's bytes (ASCII or binary) into a mesh with shared vertices.
pub fn parse_stl(bytes: &[u8]) -> Result<Mesh, MeshError> {
    let ascii = bytes.trim_ascii_start().starts_with(b"solid") && is_probably_text(bytes);
    if !ascii {
        if bytes.len() < 84 {
            return Err(MeshError::Read(format!(
                "not an STL file: {} bytes, shorter than a binary STL header (84 bytes)",
                bytes.len()
            )));
        }
        let declared = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if declared > MAX_TRIANGLES as u64 {
            return Err(MeshError::TooLarge(declared));
        }
        let need = 84 + 50 * declared;
        if (bytes.len() as u64) < need {
            return Err(MeshError::Truncated {
                declared,
                need,
                got: bytes.len() as u64,
            });
        }
    } else if bytes.len() / ASCII_FACET_BYTES > MAX_TRIANGLES {
        return Err(MeshError::TooLarge(
            (bytes.len() / ASCII_FACET_BYTES) as u64,
        ));
    }
    let indexed = stl_io::read_stl(&mut Cursor::new(bytes)).map_err(|e| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            MeshError::Read("not an STL file: it ends in the middle of a triangle".into())
        } else {
            MeshError::Read(format!("not an STL file: {e}"))
        }
    })?;
    if indexed.faces.is_empty() {
        return Err(MeshError::Empty);
    }
    if indexed.faces.len() > MAX_TRIANGLES {
        return Err(MeshError::TooLarge(indexed.faces.len() as u64));
    }
    let vertices: Vec<DVec3> = indexed
        .vertices
        .iter()
        .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .collect();
    let triangles = indexed
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    finite(Mesh {
        vertices,
        triangles,
    })
}

/// The mesh, unless a vertex is not a number (a text file can say `nan` or `1e999`).
fn finite(mesh: Mesh) -> Result<Mesh, MeshError> {
    match mesh.vertices.iter().find(|v| !v.is_finite()) {
        Some(bad) => Err(MeshError::Read(format!("a vertex is not a number: {bad}"))),
        None => Ok(mesh),
    }
}

/// Reads a Wavefront OBJ file's bytes ([`tobj`], faces triangulated) into one mesh; positions
/// equal to the bit are shared across the file's objects and groups, as STL's are.
pub fn parse_obj(bytes: &[u8]) -> Result<Mesh, MeshError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| MeshError::Read(format!("not a Wavefront OBJ file: {e}")))?;
    let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    if triangles > MAX_TRIANGLES {
        return Err(MeshError::TooLarge(triangles as u64));
    }
    let mut mesh = Mesh::default();
    let mut index: HashMap<[u32; 3], u32, FixedState> =
        HashMap::with_capacity_and_hasher(triangles, FixedState::default());
    for model in &models {
        let m = &model.mesh;
        let mut shared = Vec::with_capacity(m.positions.len() / 3);
        for p in m.positions.chunks_exact(3) {
            let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
            let next = mesh.vertices.len() as u32;
            let i = *index.entry(key).or_insert_with(|| {
                mesh.vertices
                    .push(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                next
            });
            shared.push(i);
        }
        for t in m.indices.chunks_exact(3) {
            let corner = |k: usize| shared.get(t[k] as usize).copied();
            match (corner(0), corner(1), corner(2)) {
                (Some(a), Some(b), Some(c)) => mesh.triangles.push([a, b, c]),
                _ => {
                    return Err(MeshError::Read(
                        "a face names a vertex the file does not have".into(),
                    ));
                }
            }
        }
    }
    if mesh.triangles.is_empty() {
        return Err(MeshError::Empty);
    }
    finite(mesh)
}

/// Whether `path` names an OBJ mesh (else STL).
fn is_obj(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// Whether the first kilobyte looks like text (an ASCII STL), not a binary header that happens
/// to begin with "solid" (several exporters write that).
fn is_probably_text(bytes: &[u8]) -> bool {
    bytes
        .iter()
        .take(1024)
        .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace())
}

/// The twice-area of a triangle, mm².
fn twice_area(m: &Mesh, t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| m.vertices[i as usize]);
    (b - a).cross(c - a).length()
}

/// Maps keyed by edges: a fast deterministic hasher (SipHash took most of the closed-body check
/// of a million triangles).
type EdgeMap<V> = HashMap<u64, V, FixedState>;

fn edge_map<V>(capacity: usize) -> EdgeMap<V> {
    HashMap::with_capacity_and_hasher(capacity, FixedState::default())
}

/// An undirected edge between two vertices, as one number.
fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    ((lo as u64) << 32) | hi as u64
}

/// Checks that the mesh is one closed body: every edge shared by exactly two triangles (of those
/// with area), one connected piece, and at most [`MAX_DEGENERATE_SHARE`] of triangles without
/// area (which are then ignored). Returns the mesh without the degenerate triangles.
pub fn check_closed_body(mesh: &Mesh) -> Result<Mesh, MeshError> {
    let total = mesh.triangles.len();
    if total == 0 {
        return Err(MeshError::Empty);
    }
    let kept: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| twice_area(mesh, t) > 2.0 * DEGENERATE_AREA)
        .collect();
    let bad = total - kept.len();
    if bad as f64 > MAX_DEGENERATE_SHARE * total as f64 {
        return Err(MeshError::Degenerate { bad, total });
    }
    // Edge → the triangles on it.
    let mut edges: EdgeMap<(u32, u32, u8)> = edge_map(kept.len() * 3 / 2);
    for (ti, t) in kept.iter().enumerate() {
        for e in 0..3 {
            let key = edge_key(t[e], t[(e + 1) % 3]);
            let slot = edges.entry(key).or_insert((ti as u32, u32::MAX, 0));
            if slot.2 == 1 {
                slot.1 = ti as u32;
            }
            slot.2 = slot.2.saturating_add(1);
        }
    }
    let open: Vec<u64> = edges
        .iter()
        .filter(|(_, s)| s.2 == 1)
        .map(|(k, _)| *k)
        .collect();
    if let Some(&first) = open.iter().min() {
        let p = mesh.vertices[(first >> 32) as usize];
        return Err(MeshError::NotClosed {
            open: open.len(),
            at: [p.x, p.y, p.z],
        });
    }
    let shared = edges.values().filter(|s| s.2 > 2).count();
    if shared > 0 {
        return Err(MeshError::NonManifold(shared));
    }
    // Connected pieces, by union–find over the triangles sharing an edge.
    let mut parent: Vec<u32> = (0..kept.len() as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    for s in edges.values() {
        let (a, b) = (root(&mut parent, s.0), root(&mut parent, s.1));
        if a != b {
            parent[a as usize] = b;
        }
    }
    let bodies = (0..kept.len() as u32)
        .filter(|&i| root(&mut parent, i) == i)
        .count();
    if bodies > 1 {
        return Err(MeshError::SeveralBodies(bodies));
    }
    Ok(Mesh {
        vertices: mesh.vertices.clone(),
        triangles: kept,
    })
}

/// The mesh scaled by `scale`, turned by `rotate_x_deg` about the x axis (90 stands a Y-up
/// export upright), and moved so that it stands on z = 0 with its footprint's bounding box
/// centred on the origin.
pub fn place(mesh: &Mesh, scale: f64, rotate_x_deg: f64) -> Mesh {
    let (s, c) = rotate_x_deg.to_radians().sin_cos();
    let mut vertices: Vec<DVec3> = mesh
        .vertices
        .iter()
        .map(|v| {
            let v = *v * scale;
            DVec3::new(v.x, c * v.y - s * v.z, s * v.y + c * v.z)
        })
        .collect();
    let (lo, hi) = vertices.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let shift = DVec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z);
    for v in &mut vertices {
        *v -= shift;
    }
    Mesh {
        vertices,
        triangles: mesh.triangles.clone(),
    }
}

/// Lowest and highest z of the mesh.
pub fn z_range(mesh: &Mesh) -> (f64, f64) {
    mesh.vertices
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v.z), hi.max(v.z))
        })
}

/// The outer outline (counter-clockwise) of the mesh at each of `heights` (ascending).
pub fn slice_outlines(mesh: &Mesh, heights: &[f64]) -> Result<Vec<Vec<DVec2>>, MeshError> {
    // Each triangle goes to the planes its z-range straddles.
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); heights.len()];
    for (ti, t) in mesh.triangles.iter().enumerate() {
        let zs = t.map(|i| mesh.vertices[i as usize].z);
        let (lo, hi) = (zs[0].min(zs[1]).min(zs[2]), zs[0].max(zs[1]).max(zs[2]));
        // Planes h with lo < h ≤ hi (a vertex on a plane counts as above it).
        let first = heights.partition_point(|&h| h <= lo);
        let last = heights.partition_point(|&h| h <= hi);
        for bucket in &mut buckets[first..last] {
            bucket.push(ti as u32);
        }
    }
    let outlines = crate::parallel::map_ranges(heights.len(), 8, |range| {
        range
            .map(|k| outline_at(mesh, &buckets[k], heights[k]))
            .collect()
    });
    outlines.into_iter().collect()
}

/// The outer outline of the plane z = `h` through the triangles `tris` that straddle it.
fn outline_at(mesh: &Mesh, tris: &[u32], h: f64) -> Result<Vec<DVec2>, MeshError> {
    // Every straddling triangle crosses the plane on two edges: one segment between them.
    let mut segments: Vec<[u64; 2]> = Vec::with_capacity(tris.len());
    let mut points: EdgeMap<DVec2> = edge_map(tris.len());
    for &ti in tris {
        let t = mesh.triangles[ti as usize];
        let mut ends = [0u64; 2];
        let mut found = 0;
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let (pa, pb) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
            if (pa.z >= h) != (pb.z >= h) && found < 2 {
                let key = edge_key(a, b);
                let f = (h - pa.z) / (pb.z - pa.z);
                points
                    .entry(key)
                    .or_insert_with(|| pa.truncate().lerp(pb.truncate(), f));
                ends[found] = key;
                found += 1;
            }
        }
        if found == 2 {
            segments.push(ends);
        }
    }
    if segments.is_empty() {
        return Err(MeshError::EmptySlice { z: h });
    }
    // Chain the segments through the edges they share (each edge is on two of them).
    let mut by_edge: EdgeMap<[u32; 2]> = edge_map(segments.len());
    for (si, s) in segments.iter().enumerate() {
        for &e in s {
            let slot = by_edge.entry(e).or_insert([u32::MAX; 2]);
            if slot[0] == u32::MAX {
                slot[0] = si as u32;
            } else {
                slot[1] = si as u32;
            }
        }
    }
    let mut used = vec![false; segments.len()];
    let mut outlines: Vec<Vec<DVec2>> = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        let mut outline = Vec::new();
        let (mut seg, mut edge) = (start, segments[start][1]);
        used[start] = true;
        outline.push(points[&segments[start][0]]);
        loop {
            outline.push(points[&edge]);
            let next = by_edge[&edge]
                .into_iter()
                .find(|&s| s != u32::MAX && s as usize != seg);
            match next {
                Some(s) if !used[s as usize] => {
                    seg = s as usize;
                    used[seg] = true;
                    let [a, b] = segments[seg];
                    edge = if a == edge { b } else { a };
                }
                _ => break,
            }
        }
        let outline = dedup_closed(&outline);
        if outline.len() >= 3 {
            outlines.push(outline);
        }
    }
    let outer = outlines
        .iter()
        .enumerate()
        .max_by(|a, b| signed_area(a.1).abs().total_cmp(&signed_area(b.1).abs()))
        .map(|(i, _)| i)
        .ok_or(MeshError::EmptySlice { z: h })?;
    let beside = outlines
        .iter()
        .enumerate()
        .filter(|&(i, o)| {
            i != outer
                && signed_area(o).abs() > NOISE_AREA
                && !contains_point(&outlines[outer], o[0])
        })
        .count();
    if beside > 0 {
        return Err(MeshError::SeveralOutlines {
            z: h,
            outlines: beside + 1,
        });
    }
    let mut outline = outlines.swap_remove(outer);
    if signed_area(&outline) < 0.0 {
        outline.reverse();
    }
    Ok(outline)
}

/// The wall sections from the outlines at `heights`: each outline moved inward by `inset`
/// exactly ([`crate::base_fill::inward_offset`]: every point of the path `inset` from the
/// surface, so the bead's outside never pokes out of the model at a corner), sampled at
/// `samples` points of equal arc length, and turned to the start that twists least against the
/// section below; section 0 lies on the bed (z = 0). An outline with nothing left inside the
/// inset (the vessel narrower than a bead there) is an error at its height.
pub fn wall_sections(
    outlines: &[Vec<DVec2>],
    heights: &[f64],
    samples: usize,
    inset: f64,
) -> Result<Vec<Section>, MeshError> {
    // The offsets, on both cores (a few hundred outlines of a thousand points); outlines far
    // denser than the path are thinned first (the offset costs with their points).
    let rings: Vec<Option<Vec<DVec2>>> = crate::parallel::map_ranges(outlines.len(), 16, |r| {
        outlines[r]
            .iter()
            .map(|outline| {
                let dense = if outline.len() > 8 * samples {
                    resample_closed(outline, 8 * samples)
                } else {
                    outline.clone()
                };
                let inside = crate::base_fill::inward_offset(&dense, inset)?;
                Some(resample_closed(&inside, samples))
            })
            .collect()
    });
    let mut sections: Vec<Section> = Vec::with_capacity(outlines.len());
    let mut below: Option<Vec<DVec2>> = None;
    for (k, (ring, &h)) in rings.into_iter().zip(heights).enumerate() {
        let Some(mut xy) = ring else {
            return Err(MeshError::NarrowerThanABead {
                z: h,
                width: 2.0 * inset,
            });
        };
        if let Some(prev) = &below {
            let o = min_twist_offset(prev, &xy);
            xy.rotate_left(o);
        }
        let z = if k == 0 { 0.0 } else { h };
        sections.push(Section {
            points: xy.iter().map(|p| p.extend(z)).collect(),
        });
        below = Some(xy);
    }
    Ok(sections)
}

/// A closed solid of revolution — a thrown pot's shape: rings of `n` points at `rings` heights
/// from 0 to `height`, radius `radius(z)`, closed by a fan at the bottom and at the top, faces
/// outward. For tests, benchmarks and examples of meshes.
pub fn revolution(n: usize, rings: usize, height: f64, radius: impl Fn(f64) -> f64) -> Mesh {
    let (n, rings) = (n.max(3), rings.max(2));
    let mut m = Mesh::default();
    for k in 0..rings {
        let z = height * k as f64 / (rings - 1) as f64;
        let r = radius(z);
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            m.vertices.push(DVec3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    let (bottom, top) = (m.vertices.len() as u32, m.vertices.len() as u32 + 1);
    m.vertices.push(DVec3::ZERO);
    m.vertices.push(DVec3::new(0.0, 0.0, height));
    let at = |k: usize, i: usize| (k * n + i % n) as u32;
    for k in 0..rings - 1 {
        for i in 0..n {
            m.triangles.push([at(k, i), at(k, i + 1), at(k + 1, i + 1)]);
            m.triangles.push([at(k, i), at(k + 1, i + 1), at(k + 1, i)]);
        }
    }
    for i in 0..n {
        m.triangles.push([bottom, at(0, i + 1), at(0, i)]);
        m.triangles
            .push([top, at(rings - 1, i), at(rings - 1, i + 1)]);
    }
    m
}

/// A placed mesh cut at the layer heights: the outer outline at each, and the pitch.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSlices {
    pub outlines: Vec<Vec<DVec2>>,
    pub heights: Vec<f64>,
    pub pitch: f64,
}

/// The mesh file of `source`, relative to the design's folder `base`.
pub fn resolve(source: &MeshSource, base: Option<&Path>) -> PathBuf {
    match base {
        Some(b) if source.path.is_relative() => b.join(&source.path),
        _ => source.path.clone(),
    }
}

/// A problem with the mesh file at `path`, as the design's error on `shape.mesh.path`.
pub(crate) fn mesh_field_error(path: &Path, e: impl std::fmt::Display) -> FieldError {
    FieldError::new("shape.mesh.path", format!("{}: {e}", path.display()))
}

/// Reads the mesh file at `path`, checks it is one closed body and places it as `source` says.
pub fn load_placed(path: &Path, source: &MeshSource) -> Result<Mesh, FieldError> {
    let len = std::fs::metadata(path)
        .map_err(|e| mesh_field_error(path, format!("cannot read: {e}")))?
        .len();
    // A binary file is 50 bytes a triangle, an ASCII one at least 100: twice that is the most
    // a file of MAX_TRIANGLES can need (4 GB), read into memory.
    if len > 84 + 2 * ASCII_FACET_BYTES as u64 * MAX_TRIANGLES as u64 {
        return Err(mesh_field_error(path, MeshError::TooLarge(len / 50)));
    }
    let bytes =
        std::fs::read(path).map_err(|e| mesh_field_error(path, format!("cannot read: {e}")))?;
    let parsed = if is_obj(path) {
        parse_obj(&bytes)
    } else {
        parse_stl(&bytes)
    };
    let mesh = parsed.map_err(|e| mesh_field_error(path, e))?;
    let mesh = check_closed_body(&mesh).map_err(|e| mesh_field_error(path, e))?;
    Ok(place(&mesh, source.scale, source.rotate_x))
}

/// The placed mesh cut into layers of about `layer_height` ([`layer_heights`]).
pub fn slices(mesh: &Mesh, layer_height: f64, path: &Path) -> Result<MeshSlices, FieldError> {
    let (_, top) = z_range(mesh);
    if top.is_nan() || top <= layer_height {
        return Err(mesh_field_error(
            path,
            format!("{top:.3} mm tall: less than one layer ({layer_height} mm)"),
        ));
    }
    let layers = top / layer_height;
    if layers > 1e5 {
        return Err(mesh_field_error(
            path,
            format!(
                "{top:.0} mm tall: {layers:.0} layers of {layer_height} mm (check shape.mesh.scale)"
            ),
        ));
    }
    let (heights, pitch) = layer_heights(top, layer_height);
    let outlines = slice_outlines(mesh, &heights).map_err(|e| mesh_field_error(path, e))?;
    Ok(MeshSlices {
        outlines,
        heights,
        pitch,
    })
}

/// The heights a mesh `height` mm tall is sliced at for layers of about `layer_height`: L layers
/// of `height / L`, section 0 just above the bed and the last just below the top (a plane
/// through the very bottom or top face would cut nothing). Returns the heights and the pitch.
pub fn layer_heights(height: f64, layer_height: f64) -> (Vec<f64>, f64) {
    let layers = ((height / layer_height).round() as usize).max(1);
    let pitch = height / layers as f64;
    let eps = (pitch * 1e-3).min(1e-3);
    let heights = (0..=layers)
        .map(|k| (k as f64 * pitch).clamp(eps, height - eps))
        .collect();
    (heights, pitch)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed cylinder of `n` sides, radius r, height h, centred on the origin.
    pub(crate) fn cylinder(n: usize, r: f64, h: f64) -> Mesh {
        revolution(n, 2, h, |_| r)
    }

    #[test]
    fn a_cylinder_slices_to_its_circle() {
        let m = check_closed_body(&cylinder(64, 30.0, 50.0)).unwrap();
        let (heights, pitch) = layer_heights(50.0, 2.0);
        assert_eq!((heights.len(), pitch), (26, 2.0));
        let outlines = slice_outlines(&m, &heights).unwrap();
        for o in &outlines {
            assert!(signed_area(o) > 0.0, "counter-clockwise");
            for p in o {
                // On the 64-gon: between its inscribed and circumscribed radius.
                let r = p.length();
                assert!(r <= 30.0 + 1e-9 && r >= 30.0 * (std::f64::consts::PI / 64.0).cos() - 1e-9);
            }
        }
    }

    #[test]
    fn broken_meshes_are_refused_with_the_reason() {
        let m = cylinder(16, 20.0, 30.0);
        // An open mesh: one triangle taken away.
        let mut open = m.clone();
        open.triangles.pop();
        assert!(matches!(
            check_closed_body(&open),
            Err(MeshError::NotClosed { open: 3, .. })
        ));
        // Two bodies.
        let mut two = m.clone();
        let offset = two.vertices.len() as u32;
        let other = cylinder(16, 20.0, 30.0);
        two.vertices.extend(
            other
                .vertices
                .iter()
                .map(|v| *v + DVec3::new(100.0, 0.0, 0.0)),
        );
        two.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
        assert_eq!(check_closed_body(&two), Err(MeshError::SeveralBodies(2)));
        // …which slice into two outlines side by side.
        let err = slice_outlines(&two, &[10.0]).unwrap_err();
        assert!(
            matches!(err, MeshError::SeveralOutlines { outlines: 2, .. }),
            "{err}"
        );
        // A doubled face.
        let mut doubled = m.clone();
        doubled.triangles.push(m.triangles[0]);
        assert!(matches!(
            check_closed_body(&doubled),
            Err(MeshError::NonManifold(_))
        ));
        // Many triangles without area.
        let mut slivers = m.clone();
        for _ in 0..10 {
            slivers.triangles.push([0, 0, 1]);
        }
        assert!(matches!(
            check_closed_body(&slivers),
            Err(MeshError::Degenerate { bad: 10, .. })
        ));
        // A few are tolerated and left out.
        let mut few = cylinder(200, 20.0, 30.0);
        few.triangles.push([0, 0, 1]);
        assert_eq!(check_closed_body(&few).unwrap().triangles.len(), 800);
    }

    #[test]
    fn a_hollow_vessel_keeps_its_outer_wall() {
        // A thick-walled tube: outer and inner cylinders joined at top and bottom by annuli.
        let (n, ro, ri, h) = (48u32, 30.0, 26.0, 40.0);
        let mut m = Mesh::default();
        for (r, z) in [(ro, 0.0), (ro, h), (ri, 0.0), (ri, h)] {
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                m.vertices.push(DVec3::new(r * a.cos(), r * a.sin(), z));
            }
        }
        let ring = |k: u32, i: u32| k * n + i % n;
        for i in 0..n {
            let j = i + 1;
            // outer wall (outward), inner wall (inward), bottom and top annuli.
            m.triangles.push([ring(0, i), ring(0, j), ring(1, j)]);
            m.triangles.push([ring(0, i), ring(1, j), ring(1, i)]);
            m.triangles.push([ring(2, i), ring(3, j), ring(2, j)]);
            m.triangles.push([ring(2, i), ring(3, i), ring(3, j)]);
            m.triangles.push([ring(0, i), ring(2, j), ring(0, j)]);
            m.triangles.push([ring(0, i), ring(2, i), ring(2, j)]);
            m.triangles.push([ring(1, i), ring(1, j), ring(3, j)]);
            m.triangles.push([ring(1, i), ring(3, j), ring(3, i)]);
        }
        let m = check_closed_body(&m).unwrap();
        let outlines = slice_outlines(&m, &[20.0]).unwrap();
        let r = outlines[0].iter().map(|p| p.length()).fold(0.0, f64::max);
        assert!((r - ro).abs() < 1e-9, "the outer wall: {r}");
    }

    #[test]
    fn truncated_and_absurd_files_are_refused_before_reading() {
        let mut bytes = vec![0u8; 84];
        bytes[80..84].copy_from_slice(&1000u32.to_le_bytes());
        bytes.extend(vec![0u8; 50 * 999]);
        assert!(matches!(
            parse_stl(&bytes),
            Err(MeshError::Truncated { declared: 1000, .. })
        ));
        bytes[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(parse_stl(&bytes), Err(MeshError::TooLarge(_))));
        assert!(matches!(
            parse_stl(b"solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n"),
            Err(MeshError::Read(_))
        ));
        assert!(matches!(parse_stl(&[1, 2, 3]), Err(MeshError::Read(_))));
        assert!(matches!(
            parse_stl(b"solid empty\nendsolid empty\n"),
            Err(MeshError::Empty)
        ));
    }

    #[test]
    fn an_obj_file_reads_the_same_mesh_as_its_stl() {
        let m = cylinder(12, 10.0, 20.0);
        let mut obj = String::from("# a cylinder\no cylinder\n");
        for v in &m.vertices {
            obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
        // Quads where the wall has them (tobj triangulates), triangles for the caps; a second
        // group repeats the positions it uses, as some exporters do.
        for t in &m.triangles {
            obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        let read = parse_obj(obj.as_bytes()).unwrap();
        assert_eq!(read.triangles.len(), m.triangles.len());
        assert_eq!(read.vertices.len(), m.vertices.len());
        check_closed_body(&read).unwrap();
        assert!(matches!(
            parse_obj(b"v 0 0 0\nf 1 2 3\n"),
            Err(MeshError::Read(_))
        ));
        assert!(matches!(parse_obj(b"# nothing\n"), Err(MeshError::Empty)));
    }

    #[test]
    fn binary_and_ascii_files_read_the_same_mesh() {
        let m = cylinder(12, 10.0, 20.0);
        let mut binary = Vec::new();
        crate::stl::write_binary_stl(&m, "cyl", &mut binary).unwrap();
        let mut ascii = Vec::new();
        crate::stl::write_ascii_stl(&m, "cyl", &mut ascii).unwrap();
        let (a, b) = (parse_stl(&binary).unwrap(), parse_stl(&ascii).unwrap());
        assert_eq!(a.triangles.len(), m.triangles.len());
        assert_eq!(a.vertices.len(), m.vertices.len(), "equal vertices merged");
        assert_eq!(a.triangles.len(), b.triangles.len());
        check_closed_body(&a).unwrap();
        check_closed_body(&b).unwrap();
    }
}

#[cfg(test)]
mod hostile {
    use super::*;
    use proptest::prelude::*;

    /// A small valid mesh as binary and as ASCII STL.
    fn files() -> (Vec<u8>, Vec<u8>) {
        let m = revolution(8, 3, 20.0, |z| 10.0 + z / 4.0);
        let (mut b, mut a) = (Vec::new(), Vec::new());
        crate::stl::write_binary_stl(&m, "x", &mut b).unwrap();
        crate::stl::write_ascii_stl(&m, "x", &mut a).unwrap();
        (b, a)
    }

    /// Whatever the bytes, reading, checking, placing and slicing end in a mesh or an error.
    fn survives(bytes: &[u8]) {
        for parsed in [parse_stl(bytes), parse_obj(bytes)] {
            let Ok(m) = parsed else { continue };
            let Ok(m) = check_closed_body(&m) else {
                continue;
            };
            let placed = place(&m, 1.0, 90.0);
            let (_, top) = z_range(&placed);
            if top.is_finite() && top > 1.0 && top < 1e4 {
                let (heights, _) = layer_heights(top, 1.0);
                let _ = slice_outlines(&placed, &heights);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Bytes of a valid file changed at random places: never a panic.
        #[test]
        fn mutated_files_never_panic(
            ascii in any::<bool>(),
            edits in proptest::collection::vec((any::<u16>(), any::<u8>()), 1..12),
            cut in any::<u16>(),
        ) {
            let (b, a) = files();
            let mut bytes = if ascii { a } else { b };
            for (at, v) in edits {
                let i = at as usize % bytes.len();
                bytes[i] = v;
            }
            let keep = bytes.len() - (cut as usize % 64).min(bytes.len());
            bytes.truncate(keep);
            survives(&bytes);
        }

        /// Random bytes: never a panic.
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            survives(&bytes);
        }
    }
}
