//! Image and SVG contours end to end (issue: contours from images and SVG files): generated
//! pictures and drawings written to disk, read back through the design's contour spec, sampled
//! like any contour.

use std::path::Path;

use clayloft_core::contour::{Contour, ContourError};
use clayloft_core::design::ContourSpec;
use clayloft_core::loft::sample_contour;
use glam::DVec2;
use image::{GrayImage, Luma};

/// A dark anti-aliased disk on white (4 × 4 supersampled coverage).
fn disk(w: u32, h: u32, c: DVec2, r: f64) -> GrayImage {
    GrayImage::from_fn(w, h, |x, y| {
        let mut cover = 0.0f64;
        for sy in 0..4 {
            for sx in 0..4 {
                let p = DVec2::new(
                    x as f64 + (sx as f64 + 0.5) / 4.0 - 0.5,
                    y as f64 + (sy as f64 + 0.5) / 4.0 - 0.5,
                );
                cover += ((p - c).length() <= r) as u8 as f64 / 16.0;
            }
        }
        Luma([(255.0 * (1.0 - cover)).round() as u8])
    })
}

fn image_spec(path: &str, size: f64) -> ContourSpec {
    ContourSpec::Image {
        path: path.into(),
        size,
        threshold: None,
    }
}

#[test]
fn circle_picture_comes_back_within_a_pixel_at_every_sample() {
    let dir = tempfile::tempdir().unwrap();
    // Radius 150 px: the outline's longer side is 300 px, so size = 300 mm makes 1 px = 1 mm.
    disk(420, 380, DVec2::new(200.0, 190.0), 150.0)
        .save(dir.path().join("disk.png"))
        .unwrap();
    let c = sample_contour(
        &image_spec("disk.png", 300.0),
        "shape.lower",
        DVec2::new(90.0, 95.0),
        360,
        Some(dir.path()),
    )
    .unwrap();
    // Alignment puts the anchor (x-extremes midpoint) — here the disk's centre — on (90, 95).
    for p in &c.samples {
        let r = (*p - DVec2::new(90.0, 95.0)).length();
        assert!((r - 150.0).abs() < 1.0, "sample at radius {r}");
    }
}

#[test]
fn square_keeps_its_four_corners() {
    let dir = tempfile::tempdir().unwrap();
    // Pixels 50 ..= 249 dark: the outline is the square 49.5 … 249.5 (200 px on a side).
    let img = GrayImage::from_fn(300, 300, |x, y| {
        Luma([if (50..250).contains(&x) && (50..250).contains(&y) {
            20
        } else {
            235
        }])
    });
    img.save(dir.path().join("square.png")).unwrap();
    let c =
        Contour::from_spec_in(&image_spec("square.png", 100.0), 4096, Some(dir.path())).unwrap();
    // 100 mm across: corners at (±50, ±50).
    for corner in [
        DVec2::new(50.0, 50.0),
        DVec2::new(-50.0, 50.0),
        DVec2::new(-50.0, -50.0),
        DVec2::new(50.0, -50.0),
    ] {
        let nearest = c
            .points
            .iter()
            .map(|p| p.distance(corner))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 0.5,
            "corner {corner} is {nearest} mm from the outline (1 px = 0.5 mm)"
        );
    }
    // Straight sides stay straight after simplification: few points.
    assert!(c.points.len() <= 24, "{} points", c.points.len());
}

#[test]
fn noisy_jpeg_scan_gives_one_clean_contour() {
    let dir = tempfile::tempdir().unwrap();
    let clean = disk(600, 500, DVec2::new(300.0, 250.0), 180.0);
    // Paper-grey background with a light vignette and ±30 grey-level noise (a fixed LCG).
    let mut seed: u64 = 12345;
    let noisy = GrayImage::from_fn(600, 500, |x, y| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let noise = ((seed >> 33) % 61) as f64 - 30.0;
        let vignette =
            -25.0 * ((x as f64 - 300.0).powi(2) + (y as f64 - 250.0).powi(2)) / 250_000.0;
        let v = clean.get_pixel(x, y)[0] as f64 * 0.8 + 30.0 + noise + vignette;
        Luma([v.clamp(0.0, 255.0) as u8])
    });
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 60)
        .encode_image(&noisy)
        .unwrap();
    std::fs::write(dir.path().join("scan.jpg"), bytes).unwrap();
    let spec = image_spec("scan.jpg", 360.0);
    let c = Contour::from_spec_in(&spec, 4096, Some(dir.path())).unwrap();
    // One closed, simple outline (from_spec rejects self-intersections) near the true circle.
    // The outline is centred on its bounding box, 1 px = 1 mm.
    let radii: Vec<f64> = c.points.iter().map(|p| p.length()).collect();
    let (lo, hi) = radii.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
        (lo.min(*r), hi.max(*r))
    });
    assert!(lo > 178.0 && hi < 182.0, "radius {lo} … {hi}");
}

#[test]
fn svg_circle_and_transformed_path_come_back_at_size_and_place() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("c.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100"><circle cx="50" cy="50" r="30"/></svg>"#,
    )
    .unwrap();
    let spec = ContourSpec::Svg {
        path: "c.svg".into(),
        size: 70.0,
        id: None,
    };
    let c = sample_contour(
        &spec,
        "shape.upper",
        DVec2::new(90.0, 95.0),
        200,
        Some(dir.path()),
    )
    .unwrap();
    for p in &c.samples {
        assert!(((*p - DVec2::new(90.0, 95.0)).length() - 35.0).abs() < 0.05);
    }
    // A triangle path rotated by 90° in a group: the outline turns with it.
    std::fs::write(
        dir.path().join("t.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200"><g transform="rotate(90 100 100)"><path id="tri" d="M60 60 L140 60 L100 120 Z"/></g></svg>"#,
    )
    .unwrap();
    let spec = ContourSpec::Svg {
        path: "t.svg".into(),
        size: 80.0,
        id: Some("tri".into()),
    };
    let c = Contour::from_spec_in(&spec, 4096, Some(dir.path())).unwrap();
    let (lo, hi) = c
        .points
        .iter()
        .fold((DVec2::splat(1e9), DVec2::splat(-1e9)), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    // Before the rotation 80 wide × 60 tall; after it 60 wide × 80 tall.
    assert!(
        ((hi - lo) - DVec2::new(60.0, 80.0)).length() < 1e-6,
        "{:?}",
        hi - lo
    );
}

fn error_of(spec: &ContourSpec, dir: &Path) -> String {
    match Contour::from_spec_in(spec, 4096, Some(dir)) {
        Err(e @ (ContourError::Image { .. } | ContourError::Svg { .. })) => e.to_string(),
        other => panic!("expected a file error, got {other:?}"),
    }
}

/// CRC-32 (IEEE) of PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG whose header declares `w × h` pixels and whose data stops right after it.
fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    out.extend_from_slice(&13u32.to_be_bytes());
    out.extend_from_slice(&ihdr);
    out.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    // The start of the pixel data (a zlib stream that ends early), then the end marker.
    for (kind, body) in [
        (&b"IDAT"[..], &[0x78u8, 0x9c, 0x03, 0x00][..]),
        (b"IEND", &[]),
    ] {
        let mut chunk = kind.to_vec();
        chunk.extend_from_slice(body);
        out.extend_from_slice(&(body.len() as u32).to_be_bytes());
        out.extend_from_slice(&chunk);
        out.extend_from_slice(&crc32(&chunk).to_be_bytes());
    }
    out
}

#[test]
fn bad_pictures_and_drawings_say_which_file_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    GrayImage::from_pixel(64, 64, Luma([255]))
        .save(d.join("white.png"))
        .unwrap();
    GrayImage::from_fn(64, 64, |x, _| Luma([if x < 20 { 0 } else { 255 }]))
        .save(d.join("edge.png"))
        .unwrap();
    std::fs::write(d.join("huge.png"), png_header_only(20_000, 20_000)).unwrap();
    let mut truncated = Vec::new();
    disk(100, 100, DVec2::new(50.0, 50.0), 30.0)
        .write_to(
            &mut std::io::Cursor::new(&mut truncated),
            image::ImageFormat::Png,
        )
        .unwrap();
    truncated.truncate(truncated.len() / 2);
    std::fs::write(d.join("truncated.png"), truncated).unwrap();
    std::fs::write(d.join("notes.png"), "these are my notes, not a picture").unwrap();
    std::fs::write(
        d.join("empty.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"></svg>"#,
    )
    .unwrap();
    for (file, why) in [
        ("missing.png", "no such file"),
        ("white.png", "all one tone"),
        ("edge.png", "runs off the picture's edge"),
        ("huge.png", "20000 × 20000 pixels is too large"),
        ("truncated.png", "not a picture this build can decode"),
        ("notes.png", "not a picture this build can decode"),
    ] {
        let e = error_of(&image_spec(file, 80.0), d);
        assert!(e.starts_with(file) && e.contains(why), "{file}: {e}");
    }
    let e = error_of(
        &ContourSpec::Svg {
            path: "empty.svg".into(),
            size: 80.0,
            id: None,
        },
        d,
    );
    assert!(
        e.starts_with("empty.svg") && e.contains("no closed path"),
        "{e}"
    );
    let e = error_of(
        &ContourSpec::Svg {
            path: "nope.svg".into(),
            size: 80.0,
            id: None,
        },
        d,
    );
    assert!(e.contains("no such file"), "{e}");
}
