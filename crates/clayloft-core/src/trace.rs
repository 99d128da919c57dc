//! Contours from pictures (SPEC §1.1, the paper's "extracts continuous pixels in the image and
//! generates contour curves"): grey scale → threshold (Otsu's, or the user's) → which tone is the
//! shape (the one that does not fill the picture's border) → the outer boundary of the largest
//! shape, sub-pixel, by marching squares (holes and specks ignored) → smoothed where the eye sees
//! no corner → simplified → scaled so its longer side is `size` mm.
//!
//! Coordinates: pixel centres at integers, image y pointing down; the contour is returned in mm
//! with y up (as the picture looks from above the bed), centred on its bounding box.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec2;
pub use image::GrayImage;

use crate::geometry::signed_area;

/// Largest picture side accepted, pixels: far beyond any photo of a pot, small enough that a
/// forged header cannot exhaust memory.
pub const MAX_SIDE: u32 = 16_384;
/// Largest picture accepted, pixels (about 100 megapixels).
pub const MAX_PIXELS: u64 = 100_000_000;
/// Smallest shape traced, in square pixels: anything smaller is a speck, not a drawing.
const MIN_AREA_PX: f64 = 64.0;
/// Turning over ±4 px sharper than this marks a corner the smoothing keeps, degrees.
const CORNER_DEG: f64 = 40.0;
/// Tolerance of the simplification, pixels.
const SIMPLIFY_PX: f64 = 0.2;

/// Why a picture gave no contour. Messages are completed with the file name by the caller.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TraceError {
    #[error("cannot read: {0}")]
    Read(String),
    #[error("not a picture this build can decode ({0})")]
    Decode(String),
    #[error("{w} × {h} pixels is too large (at most {MAX_SIDE} per side and {MAX_PIXELS} pixels)")]
    TooLarge { w: u32, h: u32 },
    #[error("the picture is all one tone: there is no shape to trace")]
    Blank,
    #[error("no shape larger than a speck at threshold {0}")]
    NoShape(u8),
    #[error(
        "the largest shape runs off the picture's edge: no closed outline (crop with a margin)"
    )]
    Open,
}

/// A traced outline in pixels, and how it was found.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Closed outline, pixel coordinates (y down), counter-clockwise as seen on screen... in
    /// y-up terms (see the module docs).
    pub points: Vec<DVec2>,
    /// The grey level separating shape from background.
    pub threshold: u8,
    /// True when the shape is darker than the background.
    pub dark_on_light: bool,
    /// Area enclosed, square pixels.
    pub area_px: f64,
}

/// Reads a picture's size from its header and refuses huge ones before decoding, then decodes it
/// (memory bounded by [`MAX_PIXELS`]) and converts it to grey.
pub fn load_grey(path: &Path) -> Result<GrayImage, TraceError> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| TraceError::Read(io_reason(&e)))?
        .with_guessed_format()
        .map_err(|e| TraceError::Read(io_reason(&e)))?;
    if reader.format().is_none() {
        return Err(TraceError::Decode("unknown file format".into()));
    }
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| TraceError::Decode(e.to_string()))?;
    if w > MAX_SIDE || h > MAX_SIDE || w as u64 * h as u64 > MAX_PIXELS {
        return Err(TraceError::TooLarge { w, h });
    }
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| TraceError::Read(io_reason(&e)))?
        .with_guessed_format()
        .map_err(|e| TraceError::Read(io_reason(&e)))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(MAX_PIXELS * 8);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| TraceError::Decode(e.to_string()))?;
    Ok(img.into_luma8())
}

fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::IsADirectory => "is a folder".into(),
        _ => e.to_string(),
    }
}

/// Otsu's threshold: the grey level t maximising the between-class variance
/// `ω₀(t)·ω₁(t)·(μ₀(t) − μ₁(t))²` of the histogram split into `≤ t` and `> t`.
/// `None` when the picture has a single tone.
pub fn otsu_threshold(hist: &[u64; 256]) -> Option<u8> {
    let total: u64 = hist.iter().sum();
    let sum_all: f64 = hist
        .iter()
        .enumerate()
        .map(|(v, n)| v as f64 * *n as f64)
        .sum();
    let (mut w0, mut sum0) = (0u64, 0.0f64);
    let mut best: Option<(f64, u8)> = None;
    for (t, &n) in hist.iter().enumerate().take(255) {
        w0 += n;
        sum0 += t as f64 * n as f64;
        let w1 = total - w0;
        if w0 == 0 || w1 == 0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0 as f64, (sum_all - sum0) / w1 as f64);
        let between = w0 as f64 * w1 as f64 * (m0 - m1) * (m0 - m1);
        if best.is_none_or(|(b, _)| between > b) {
            best = Some((between, t as u8));
        }
    }
    best.map(|(_, t)| t)
}

/// 3 × 3 box blur (separable, edges clamped): takes the grain out of scans and JPEG blocks
/// before thresholding; a straight edge's mid-grey line stays where it was.
pub fn box_blur3(img: &GrayImage) -> GrayImage {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let src = img.as_raw();
    let mut rows = vec![0u16; w * h];
    for y in 0..h {
        let r = &src[y * w..(y + 1) * w];
        let out = &mut rows[y * w..(y + 1) * w];
        for x in 0..w {
            let (a, c) = (r[x.saturating_sub(1)], r[(x + 1).min(w - 1)]);
            out[x] = a as u16 + r[x] as u16 + c as u16;
        }
    }
    let mut dst = vec![0u8; w * h];
    for y in 0..h {
        let (up, mid, down) = (y.saturating_sub(1) * w, y * w, (y + 1).min(h - 1) * w);
        for x in 0..w {
            let sum = rows[up + x] + rows[mid + x] + rows[down + x];
            dst[mid + x] = ((sum + 4) / 9) as u8;
        }
    }
    GrayImage::from_raw(w as u32, h as u32, dst).unwrap_or_else(|| img.clone())
}

/// Traces the outer boundary of the largest shape of a grey picture. `threshold` overrides
/// Otsu's; the shape is whichever side of it does not fill the picture's border.
pub fn trace_grey(img: &GrayImage, threshold: Option<u8>) -> Result<Trace, TraceError> {
    let (w, h) = img.dimensions();
    let (w, h) = (w as usize, h as usize);
    let px = img.as_raw();
    let mut hist = [0u64; 256];
    for &v in px {
        hist[v as usize] += 1;
    }
    if hist.iter().filter(|n| **n > 0).count() < 2 {
        return Err(TraceError::Blank);
    }
    let t = match threshold {
        Some(t) => t,
        None => otsu_threshold(&hist).ok_or(TraceError::Blank)?,
    };
    // f(x, y) > 0 inside the shape. With Otsu's threshold the outline runs where the grey is
    // midway between the two tones' means (the true edge of an anti-aliased shape); a manual
    // threshold is taken as given. Either sits between grey levels so no pixel is on it.
    let level = match threshold {
        Some(t) => t as f64 + 0.5,
        None => {
            let mean = |r: std::ops::Range<usize>| {
                let n: u64 = hist[r.clone()].iter().sum();
                let s: f64 = r.map(|v| v as f64 * hist[v] as f64).sum();
                s / n.max(1) as f64
            };
            let mid = 0.5 * (mean(0..t as usize + 1) + mean(t as usize + 1..256));
            mid.floor() + 0.5
        }
    };
    let t = level.floor().clamp(0.0, 255.0) as u8;
    // The background is the tone that fills the border.
    let mut light_border = 0usize;
    let mut border = 0usize;
    let mut count = |v: u8| {
        border += 1;
        light_border += (v > t) as usize;
    };
    for x in 0..w {
        count(px[x]);
        count(px[(h - 1) * w + x]);
    }
    for y in 0..h {
        count(px[y * w]);
        count(px[y * w + w - 1]);
    }
    let dark_on_light = 2 * light_border >= border;
    // Inside flags with a one-pixel background margin: (w + 2) × (h + 2), pixel (x, y) at
    // (y + 1)·pw + x + 1. `level` is half-way between grey levels, so v > level ⇔ v > ⌊level⌋.
    let pw = w + 2;
    let cut = level.floor().clamp(-1.0, 255.0) as i16;
    let mut inside = vec![0u8; pw * (h + 2)];
    for y in 0..h {
        let src = &px[y * w..(y + 1) * w];
        let dst = &mut inside[(y + 1) * pw + 1..(y + 1) * pw + 1 + w];
        for (d, &v) in dst.iter_mut().zip(src) {
            *d = ((v as i16 > cut) != dark_on_light) as u8;
        }
    }
    let f = |x: isize, y: isize| -> f64 {
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
            return -level.max(255.0 - level).max(1.0);
        }
        let v = px[y as usize * w + x as usize] as f64 - level;
        if dark_on_light { -v } else { v }
    };
    // Marching squares over cells (x, y)…(x+1, y+1), x in −1..w, y in −1..h (a background
    // margin closes every outline). Each segment runs with the shape on its left (y down), so
    // outer outlines and holes come out with opposite orientations.
    let stride = w as u64 + 2;
    let hedge = |x: isize, y: isize| ((y + 1) as u64 * stride + (x + 1) as u64) << 1;
    let vedge = |x: isize, y: isize| hedge(x, y) | 1;
    let mut next: HashMap<u64, u64> = HashMap::new();
    let mut point: HashMap<u64, DVec2> = HashMap::new();
    let cross = |ax: isize, ay: isize, bx: isize, by: isize| {
        let (fa, fb) = (f(ax, ay), f(bx, by));
        let s = fa / (fa - fb);
        DVec2::new(
            ax as f64 + (bx - ax) as f64 * s,
            ay as f64 + (by - ay) as f64 * s,
        )
    };
    for y in -1..h as isize {
        let row0 = &inside[(y + 1) as usize * pw..(y + 2) as usize * pw];
        let row1 = &inside[(y + 2) as usize * pw..(y + 3) as usize * pw];
        for xi in 0..=w {
            let (a, b, c, d) = (row0[xi], row0[xi + 1], row1[xi + 1], row1[xi]);
            // Most cells are wholly inside or outside.
            if a == b && c == d && a == d {
                continue;
            }
            let x = xi as isize - 1;
            let case = a | b << 1 | c << 2 | d << 3;
            let (top, right, bottom, left) =
                (hedge(x, y), vedge(x + 1, y), hedge(x, y + 1), vedge(x, y));
            let centre_inside = || f(x, y) + f(x + 1, y) + f(x + 1, y + 1) + f(x, y + 1) > 0.0;
            let segments: &[(u64, u64)] = match case {
                1 => &[(left, top)],
                2 => &[(top, right)],
                3 => &[(left, right)],
                4 => &[(right, bottom)],
                5 if centre_inside() => &[(right, top), (left, bottom)],
                5 => &[(left, top), (right, bottom)],
                6 => &[(top, bottom)],
                7 => &[(left, bottom)],
                8 => &[(bottom, left)],
                9 => &[(bottom, top)],
                10 if centre_inside() => &[(top, left), (bottom, right)],
                10 => &[(top, right), (bottom, left)],
                11 => &[(bottom, right)],
                12 => &[(right, left)],
                13 => &[(right, top)],
                _ => &[(top, left)], // 14
            };
            for &(a, b) in segments {
                next.insert(a, b);
                for e in [a, b] {
                    point.entry(e).or_insert_with(|| {
                        if e & 1 == 0 {
                            let (ex, ey) = edge_xy(e, stride);
                            cross(ex, ey, ex + 1, ey)
                        } else {
                            let (ex, ey) = edge_xy(e, stride);
                            cross(ex, ey, ex, ey + 1)
                        }
                    });
                }
            }
        }
    }
    // Link segments into closed outlines; keep the outer one (shape on the left, y down: negative
    // shoelace area) enclosing the most.
    let mut best: Option<(f64, Vec<DVec2>)> = None;
    let mut seen: std::collections::HashSet<u64> = std::collections::HashSet::new();
    // Walk the outlines from their smallest edge key, so a picture always gives the same
    // outline starting at the same point (HashMap order is random per run).
    let mut starts: Vec<u64> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        let mut loop_pts = Vec::new();
        let mut e = start;
        loop {
            seen.insert(e);
            loop_pts.push(point[&e]);
            match next.get(&e) {
                Some(&n) if n != start => e = n,
                _ => break,
            }
        }
        let area = -signed_area(&loop_pts);
        if area > 0.0 && best.as_ref().is_none_or(|(a, _)| area > *a) {
            best = Some((area, loop_pts));
        }
    }
    let (area_px, points) = best.ok_or(TraceError::NoShape(t))?;
    if area_px < MIN_AREA_PX {
        return Err(TraceError::NoShape(t));
    }
    let (wf, hf) = (w as f64 - 1.0, h as f64 - 1.0);
    if points
        .iter()
        .any(|p| p.x <= 0.0 || p.y <= 0.0 || p.x >= wf || p.y >= hf)
    {
        return Err(TraceError::Open);
    }
    Ok(Trace {
        points,
        threshold: t,
        dark_on_light,
        area_px,
    })
}

fn edge_xy(e: u64, stride: u64) -> (isize, isize) {
    let cell = e >> 1;
    ((cell % stride) as isize - 1, (cell / stride) as isize - 1)
}

/// Smooths an outline without rounding its corners: points where the outline turns by more than
/// `CORNER_DEG` over ±4 points stay put; the others are averaged with their neighbours
/// (`pᵢ ← ¼pᵢ₋₁ + ½pᵢ + ¼pᵢ₊₁`, three passes), which removes pixel and JPEG noise.
pub fn smooth_keeping_corners(points: &[DVec2]) -> Vec<DVec2> {
    let n = points.len();
    if n < 12 {
        return points.to_vec();
    }
    let k = 4;
    let cos_corner = CORNER_DEG.to_radians().cos();
    let turn_cos: Vec<f64> = (0..n)
        .map(|i| {
            let a = points[i] - points[(i + n - k) % n];
            let b = points[(i + k) % n] - points[i];
            a.normalize_or_zero().dot(b.normalize_or_zero())
        })
        .collect();
    // A corner is the sharpest point of a run of sharp turns; it and its neighbours stay put.
    let mut fixed = vec![false; n];
    for i in 0..n {
        let sharp = turn_cos[i] < cos_corner;
        let sharpest = (1..=k).all(|d| {
            turn_cos[i] <= turn_cos[(i + d) % n] && turn_cos[i] <= turn_cos[(i + n - d) % n]
        });
        if sharp && sharpest {
            fixed[i] = true;
        }
    }
    let mut cur = points.to_vec();
    for _ in 0..3 {
        let prev = cur.clone();
        for i in 0..n {
            if !fixed[i] {
                cur[i] = prev[(i + n - 1) % n] * 0.25 + prev[i] * 0.5 + prev[(i + 1) % n] * 0.25;
            }
        }
    }
    cur
}

/// Ramer–Douglas–Peucker on a closed outline: drops points within `tol` of the chord they would
/// be replaced by. The outline is split at its two mutually farthest points first.
pub fn simplify_closed(points: &[DVec2], tol: f64) -> Vec<DVec2> {
    let n = points.len();
    if n < 4 {
        return points.to_vec();
    }
    let far = (1..n)
        .max_by(|&a, &b| {
            points[a]
                .distance_squared(points[0])
                .total_cmp(&points[b].distance_squared(points[0]))
        })
        .unwrap_or(n / 2);
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[far] = true;
    let mut stack = vec![(0usize, far), (far, n)];
    while let Some((a, b)) = stack.pop() {
        if b - a < 2 {
            continue;
        }
        let (pa, pb) = (points[a], points[b % n]);
        let d = pb - pa;
        let len = d.length();
        let (mut worst, mut at) = (0.0, a);
        for (i, p) in points.iter().enumerate().take(b).skip(a + 1) {
            let dist = if len > 0.0 {
                d.perp_dot(*p - pa).abs() / len
            } else {
                p.distance(pa)
            };
            if dist > worst {
                worst = dist;
                at = i;
            }
        }
        if worst > tol {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    points
        .iter()
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|(p, _)| *p)
        .collect()
}

/// The traced outline in mm, y up, centred on its bounding box, longer side `size` mm.
pub fn outline_mm(trace_px: &[DVec2], size: f64) -> Vec<DVec2> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in trace_px {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let span = (hi - lo).max_element().max(1e-9);
    let scale = size / span;
    let mid = (lo + hi) * 0.5;
    trace_px
        .iter()
        .map(|p| DVec2::new(p.x - mid.x, mid.y - p.y) * scale)
        .collect()
}

/// What the app shows while the user adjusts an image contour: the picture (at most
/// `max_side` pixels across) and the outline traced at `threshold` (None = Otsu's), in that
/// picture's pixels; or why there is none.
pub struct Preview {
    pub thumbnail: GrayImage,
    /// Thumbnail pixels per picture pixel.
    pub scale: f64,
    pub outline: Result<Trace, TraceError>,
}

/// Loads a picture and traces it for the preview (same chain as the contour).
pub fn preview(path: &Path, threshold: Option<u8>, max_side: u32) -> Result<Preview, TraceError> {
    let img = load_grey(path)?;
    let scale = (max_side as f64 / img.width().max(img.height()) as f64).min(1.0);
    let thumbnail = if scale < 1.0 {
        image::imageops::thumbnail(
            &img,
            (img.width() as f64 * scale).round().max(1.0) as u32,
            (img.height() as f64 * scale).round().max(1.0) as u32,
        )
    } else {
        img.clone()
    };
    let outline = trace_grey(&box_blur3(&img), threshold);
    Ok(Preview {
        thumbnail,
        scale,
        outline,
    })
}

/// The whole picture-to-outline chain on a decoded picture: trace, smooth, simplify, scale.
pub fn contour_from_grey(
    img: &GrayImage,
    threshold: Option<u8>,
    size: f64,
) -> Result<(Vec<DVec2>, Trace), TraceError> {
    let trace = trace_grey(&box_blur3(img), threshold)?;
    let smooth = smooth_keeping_corners(&trace.points);
    let simple = simplify_closed(&smooth, SIMPLIFY_PX);
    Ok((outline_mm(&simple, size), trace))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use image::Luma;

    /// A dark anti-aliased disk of radius r on white, centre (cx, cy), 4×4 supersampled.
    pub fn disk(w: u32, h: u32, cx: f64, cy: f64, r: f64) -> GrayImage {
        GrayImage::from_fn(w, h, |x, y| {
            let mut cover = 0.0f64;
            for sy in 0..4 {
                for sx in 0..4 {
                    let px = x as f64 + (sx as f64 + 0.5) / 4.0 - 0.5;
                    let py = y as f64 + (sy as f64 + 0.5) / 4.0 - 0.5;
                    if (px - cx).hypot(py - cy) <= r {
                        cover += 1.0 / 16.0;
                    }
                }
            }
            Luma([(255.0 * (1.0 - cover)).round() as u8])
        })
    }

    #[test]
    fn otsu_splits_two_tones_between_them() {
        let mut hist = [0u64; 256];
        hist[30] = 500;
        hist[200] = 1500;
        let t = otsu_threshold(&hist).unwrap();
        assert!((30..200).contains(&t), "{t}");
        hist[30] = 0;
        hist[200] = 0;
        hist[7] = 10;
        assert_eq!(otsu_threshold(&hist), None);
    }

    #[test]
    fn disk_traces_at_its_radius_within_a_quarter_pixel() {
        let img = disk(200, 160, 90.0, 75.0, 50.0);
        let t = trace_grey(&img, None).unwrap();
        assert!(t.dark_on_light);
        for p in &t.points {
            let r = (*p - DVec2::new(90.0, 75.0)).length();
            assert!((r - 50.0).abs() < 0.25, "{r}");
        }
        assert!(
            (t.area_px - std::f64::consts::PI * 2500.0).abs() < 30.0,
            "{}",
            t.area_px
        );
    }

    #[test]
    fn light_on_dark_and_holes_and_specks() {
        // A white ring (outer 40, inner 20) on black, plus a white speck: the ring's outer edge.
        let mut img = GrayImage::from_fn(160, 160, |x, y| {
            let r = (x as f64 - 70.0).hypot(y as f64 - 80.0);
            Luma([if (20.0..=40.0).contains(&r) { 240 } else { 10 }])
        });
        img.put_pixel(140, 20, Luma([250]));
        let t = trace_grey(&img, None).unwrap();
        assert!(!t.dark_on_light);
        let r_min = t
            .points
            .iter()
            .map(|p| (*p - DVec2::new(70.0, 80.0)).length())
            .fold(f64::INFINITY, f64::min);
        assert!(r_min > 39.0, "{r_min}");
    }

    #[test]
    fn blank_open_and_speck_pictures_are_errors() {
        assert_eq!(
            trace_grey(&GrayImage::from_pixel(50, 50, Luma([255])), None),
            Err(TraceError::Blank)
        );
        // A dark half-plane runs off the edge.
        let half = GrayImage::from_fn(60, 60, |x, _| Luma([if x < 30 { 0 } else { 255 }]));
        assert_eq!(trace_grey(&half, None), Err(TraceError::Open));
        let mut speck = GrayImage::from_pixel(60, 60, Luma([255]));
        speck.put_pixel(30, 30, Luma([0]));
        assert!(matches!(
            trace_grey(&speck, None),
            Err(TraceError::NoShape(_))
        ));
    }

    #[test]
    fn rdp_keeps_corners_of_a_dense_square() {
        let mut sq = Vec::new();
        for i in 0..40 {
            sq.push(DVec2::new(i as f64, 0.0));
        }
        for i in 0..40 {
            sq.push(DVec2::new(40.0, i as f64));
        }
        for i in 0..40 {
            sq.push(DVec2::new(40.0 - i as f64, 40.0));
        }
        for i in 0..40 {
            sq.push(DVec2::new(0.0, 40.0 - i as f64));
        }
        let s = simplify_closed(&sq, 0.2);
        assert_eq!(s.len(), 4, "{s:?}");
    }
}
