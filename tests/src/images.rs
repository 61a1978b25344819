//! Reference images compared with a perceptual metric.
//!
//! The metric is the CIE76 colour difference (ΔE in CIELAB) per pixel, summarised by its mean
//! and 99th percentile: a few edge pixels may differ between drivers, a shifted or recoloured
//! part may not. References live in `tests/references/`; they are small and were made on
//! lavapipe (Mesa 22.3.6, llvmpipe LLVM 15, Debian 12).
//!
//! - A missing reference fails the test unless `CADR_CREATE_REFERENCES=1`, which writes it.
//! - A mismatch writes `NAME.new.png` beside the reference; `CADR_UPDATE_REFERENCES=1` accepts
//!   the new image instead of failing.

use std::path::PathBuf;

use image::RgbaImage;

/// How far two images are apart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDifference {
    /// Mean ΔE over all pixels.
    pub mean: f64,
    /// 99th percentile of ΔE.
    pub p99: f64,
    /// Largest ΔE.
    pub max: f64,
}

/// How much difference a test accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Largest accepted mean ΔE.
    pub mean: f64,
    /// Largest accepted 99th-percentile ΔE.
    pub p99: f64,
}

/// Tight enough to catch a wrong colour on a small part, loose enough for rasterisation
/// differences on edges between drivers.
pub const DEFAULT_TOLERANCE: Tolerance = Tolerance {
    mean: 0.5,
    p99: 8.0,
};

fn srgb_to_linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// CIELAB (D65) of an sRGB pixel.
pub fn to_lab(pixel: [u8; 3]) -> [f64; 3] {
    let [r, g, b] = pixel.map(srgb_to_linear);
    let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
    let f = |t: f64| {
        if t > 0.008856 {
            t.cbrt()
        } else {
            7.787 * t + 16.0 / 116.0
        }
    };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Compares two images of equal size.
pub fn compare(a: &RgbaImage, b: &RgbaImage) -> Result<ImageDifference, String> {
    if a.dimensions() != b.dimensions() {
        return Err(format!(
            "sizes differ: {:?} vs {:?}",
            a.dimensions(),
            b.dimensions()
        ));
    }
    let mut deltas: Vec<f64> = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| {
            let (l1, l2) = (to_lab([p[0], p[1], p[2]]), to_lab([q[0], q[1], q[2]]));
            ((l1[0] - l2[0]).powi(2) + (l1[1] - l2[1]).powi(2) + (l1[2] - l2[2]).powi(2)).sqrt()
        })
        .collect();
    if deltas.is_empty() {
        return Ok(ImageDifference {
            mean: 0.0,
            p99: 0.0,
            max: 0.0,
        });
    }
    let mean = deltas.iter().sum::<f64>() / deltas.len() as f64;
    deltas.sort_by(f64::total_cmp);
    let p99 = deltas[((deltas.len() as f64 * 0.99) as usize).min(deltas.len() - 1)];
    let max = deltas[deltas.len() - 1];
    Ok(ImageDifference { mean, p99, max })
}

fn references_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("references")
}

fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Compares `image` with the reference `NAME.png`, following the workflow in the module docs.
pub fn assert_matches_reference(name: &str, image: &RgbaImage, tolerance: Tolerance) {
    let dir = references_dir();
    let reference_path = dir.join(format!("{name}.png"));
    let new_path = dir.join(format!("{name}.new.png"));
    let save = |path: &PathBuf| {
        std::fs::create_dir_all(&dir).expect("create tests/references");
        image
            .save(path)
            .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
    };
    let reference = match image::open(&reference_path) {
        Ok(reference) => reference.to_rgba8(),
        Err(_) if env_flag("CADR_CREATE_REFERENCES") || env_flag("CADR_UPDATE_REFERENCES") => {
            save(&reference_path);
            eprintln!("created reference {}", reference_path.display());
            return;
        }
        Err(error) => {
            save(&new_path);
            panic!(
                "reference {} is missing ({error}); the rendered image is at {}. Run with CADR_CREATE_REFERENCES=1 to create it.",
                reference_path.display(),
                new_path.display()
            );
        }
    };
    let difference = compare(image, &reference).unwrap_or_else(|e| panic!("{name}: {e}"));
    if difference.mean <= tolerance.mean && difference.p99 <= tolerance.p99 {
        let _ = std::fs::remove_file(&new_path);
        return;
    }
    if env_flag("CADR_UPDATE_REFERENCES") {
        save(&reference_path);
        eprintln!(
            "updated reference {} ({difference:?})",
            reference_path.display()
        );
        return;
    }
    save(&new_path);
    panic!(
        "{name} differs from its reference: {difference:?} exceeds {tolerance:?}; new image at {}",
        new_path.display()
    );
}

/// Fraction of pixels that differ from the top-left (background) pixel.
pub fn covered_fraction(image: &RgbaImage) -> f64 {
    let background = *image.get_pixel(0, 0);
    let covered = image.pixels().filter(|p| **p != background).count();
    covered as f64 / (image.width() * image.height()).max(1) as f64
}
