//! Image contours: a 4000 × 4000 photo-like picture (a petal shape, shaded background, grain) to
//! a contour. Target: under 150 ms on the 2-core development machine (release, one core).

use clayloft_core::trace::contour_from_grey;
use criterion::{Criterion, criterion_group, criterion_main};
use image::{GrayImage, Luma};

fn photo(side: u32) -> GrayImage {
    let c = side as f64 / 2.0;
    let mut seed: u64 = 7;
    GrayImage::from_fn(side, side, |x, y| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let grain = ((seed >> 33) % 41) as f64 - 20.0;
        let (dx, dy) = (x as f64 - c, y as f64 - c);
        let r = dx.hypot(dy);
        let edge = 0.36 * side as f64 + 0.06 * side as f64 * (5.0 * dy.atan2(dx)).cos();
        let shade = 20.0 * (x as f64 / side as f64);
        let v = if r < edge { 60.0 } else { 210.0 } + grain + shade;
        Luma([v.clamp(0.0, 255.0) as u8])
    })
}

fn bench(c: &mut Criterion) {
    let img = photo(4000);
    let mut g = c.benchmark_group("image_contour");
    g.sample_size(20);
    g.bench_function("photo_4000x4000_to_contour", |b| {
        b.iter(|| contour_from_grey(std::hint::black_box(&img), None, 80.0).unwrap())
    });
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    g.bench_function("decode_png_4000x4000_grey", |b| {
        b.iter(|| {
            image::load_from_memory(std::hint::black_box(&png))
                .unwrap()
                .into_luma8()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
