//! A small picture of the vessel for the G-code header, drawn without a window (so headless
//! `clayloft gcode` writes it): the toolpath seen from the front and a little above, every
//! point a dot, nearer and higher dots lighter, clay-coloured on a transparent background. Written
//! as PrusaSlicer's thumbnail block (the form OctoPrint's thumbnail plugins and printer screens
//! read; Moonraker's parser reads it only in files of slicers it identifies):
//!
//! ```text
//! ; thumbnail begin 32x32 1234
//! ; iVBORw0KGgo…            (base64 of the PNG, 78 characters a line)
//! ; thumbnail end
//! ```

use base64::Engine as _;
use glam::{DVec2, DVec3};

/// The sizes written: a small one for printer screens, a larger one for host web pages.
pub const SIZES: [(u32, u32); 2] = [(32, 32), (220, 220)];

/// Points drawn at most (about one per pixel of the larger picture): a caller may thin a longer
/// path to this many before handing it over.
pub const MAX_DRAWN: usize = 40_000;

/// Draws `points` (bed frame, mm) into a `w` × `h` RGBA picture.
pub fn render(points: &[DVec3], w: u32, h: u32) -> image::RgbaImage {
    let mut img = image::RgbaImage::new(w, h);
    if points.is_empty() || w == 0 || h == 0 {
        return img;
    }
    // View: turned 30° about the vertical, looking down 20°.
    let (yaw, pitch) = (30f64.to_radians(), 20f64.to_radians());
    // About one point per pixel (at least a thousand) is enough to draw the vessel.
    let step = (points.len() / ((w * h) as usize).clamp(1_000, MAX_DRAWN)).max(1);
    let drawn = points.iter().step_by(step);
    let centre = drawn.clone().fold(DVec3::ZERO, |a, p| a + *p) / drawn.count() as f64;
    let project = |p: DVec3| -> (DVec2, f64) {
        let q = p - centre;
        let x = q.x * yaw.cos() - q.y * yaw.sin();
        let depth = q.x * yaw.sin() + q.y * yaw.cos();
        let y = q.z * pitch.cos() - depth * pitch.sin();
        (DVec2::new(x, y), depth * pitch.cos() + q.z * pitch.sin())
    };
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in points.iter().step_by(step) {
        let (s, d) = project(*p);
        lo = lo.min(s);
        hi = hi.max(s);
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    let span = (hi - lo).max_element().max(1e-9);
    let margin = 0.06 * w.min(h) as f64;
    let scale = (w.min(h) as f64 - 2.0 * margin) / span;
    let offset = DVec2::new(w as f64, h as f64) / 2.0 - (lo + hi) / 2.0 * scale;
    let mut depth_buf = vec![f64::NEG_INFINITY; (w * h) as usize];
    let radius = (w.min(h) as f64 / 110.0).max(0.6);
    // The pixel offsets of a dot, row by row: those within the radius of its centre.
    let r = radius.ceil() as i64;
    let dot: Vec<(i64, i64)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| ((dx * dx + dy * dy) as f64) <= radius * radius + 0.5)
        .collect();
    for p in points.iter().step_by(step) {
        let (s, d) = project(*p);
        let c = s * scale + offset;
        let (cx, cy) = (c.x, h as f64 - c.y);
        let shade = if dmax > dmin {
            (d - dmin) / (dmax - dmin)
        } else {
            0.5
        };
        let light = 0.45 + 0.55 * (1.0 - shade);
        // Clay: a terracotta, lighter where nearer.
        let rgb = [
            (196.0 * light + 30.0) as u8,
            (118.0 * light + 20.0) as u8,
            (78.0 * light + 15.0) as u8,
        ];
        // A dot near the picture (always, for a path of real numbers) converts its pixels without
        // the checks `as` makes for NaN and the ends of the range; the same pixels.
        let near = cx.abs() < 1e15 && cy.abs() < 1e15;
        for &(dx, dy) in &dot {
            let (x, y) = if near {
                let (x, y) = (cx + dx as f64, cy + dy as f64);
                // SAFETY: both are numbers well within i64 (the centre within 1e15, the offset
                // a few pixels), whose whole parts fit.
                unsafe { (x.to_int_unchecked::<i64>(), y.to_int_unchecked::<i64>()) }
            } else {
                ((cx + dx as f64) as i64, (cy + dy as f64) as i64)
            };
            if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                continue;
            }
            let k = (y as u32 * w + x as u32) as usize;
            // Nearer to the viewer = smaller depth value: keep the nearest.
            if -d > depth_buf[k] {
                depth_buf[k] = -d;
                img.put_pixel(
                    x as u32,
                    y as u32,
                    image::Rgba([rgb[0], rgb[1], rgb[2], 255]),
                );
            }
        }
    }
    img
}

/// The PNG of `img`.
pub fn png(img: &image::RgbaImage) -> Vec<u8> {
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    use image::ImageEncoder as _;
    encoder
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgba8,
        )
        .expect("encoding a picture into memory cannot fail");
    out
}

/// The thumbnail blocks of `points` for a G-code header.
pub fn header_blocks(points: &[DVec3]) -> String {
    let mut out = String::new();
    for (w, h) in SIZES {
        let data = base64::engine::general_purpose::STANDARD.encode(png(&render(points, w, h)));
        out.push_str(&format!(";\n; thumbnail begin {w}x{h} {}\n", data.len()));
        for chunk in data.as_bytes().chunks(78) {
            out.push_str("; ");
            out.push_str(std::str::from_utf8(chunk).expect("base64 is ASCII"));
            out.push('\n');
        }
        out.push_str("; thumbnail end\n;\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cylinder_draws_a_clay_coloured_shape_that_decodes() {
        let pts: Vec<DVec3> = (0..2000)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 100.0;
                DVec3::new(
                    90.0 + 40.0 * a.cos(),
                    95.0 + 40.0 * a.sin(),
                    k as f64 * 0.05,
                )
            })
            .collect();
        let img = render(&pts, 64, 64);
        let drawn = img.pixels().filter(|p| p[3] == 255).count();
        assert!(drawn > 300 && drawn < 64 * 64 * 9 / 10, "{drawn}");
        let block = header_blocks(&pts);
        let first = block
            .lines()
            .find(|l| l.starts_with("; thumbnail begin 32x32"))
            .unwrap();
        let len: usize = first.rsplit(' ').next().unwrap().parse().unwrap();
        let data: String = block
            .lines()
            .skip_while(|l| !l.starts_with("; thumbnail begin 32x32"))
            .skip(1)
            .take_while(|l| *l != "; thumbnail end")
            .map(|l| &l[2..])
            .collect();
        assert_eq!(data.len(), len);
        let png = base64::engine::general_purpose::STANDARD
            .decode(data)
            .unwrap();
        let back = image::load_from_memory(&png).unwrap();
        assert_eq!((back.width(), back.height()), (32, 32));
        assert!(block.lines().all(|l| l.len() <= 80 && l.starts_with(';')));
    }
}
