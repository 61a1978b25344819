//! Reference images compared with NVIDIA's FLIP, a perceptual difference metric (the `nv-flip`
//! crate, as wgpu's tests use it): per pixel an error from 0 (the same) to 1, from colour and
//! edge differences as a viewer at 0.7 m from a 24" monitor would see them, summarised by its
//! mean and 99th percentile. A few edge pixels may differ between drivers, a shifted or
//! recoloured part may not. References live in `tests/references/`; they are small and were
//! made on lavapipe (Mesa 22.3.6, llvmpipe LLVM 15, Debian 12).
//!
//! Tolerances, in FLIP's terms (measured over this suite's 2 100 comparisons on lavapipe):
//! pictures that should be the same (one scene drawn by different techniques) differed by a
//! mean of at most 0.0004 and a 99th percentile of at most 0.009; every deliberate change
//! (a moved part, a highlight, edges drawn or not) had a mean of at least 0.04.
//!
//! - A missing reference fails the test unless `CADR_CREATE_REFERENCES=1`, which writes it.
//! - A mismatch writes `NAME.new.png` beside the reference; `CADR_UPDATE_REFERENCES=1` accepts
//!   the new image instead of failing.

use std::path::PathBuf;

use cadr_core::render::Background;
use image::RgbaImage;

/// How far two images are apart, in FLIP error (0: the same, 1: as different as can be).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDifference {
    /// Mean error over all pixels.
    pub mean: f64,
    /// 99th percentile of the error.
    pub p99: f64,
    /// Largest error.
    pub max: f64,
}

impl ImageDifference {
    /// Whether the difference is within `tolerance`.
    pub fn within(&self, tolerance: Tolerance) -> bool {
        self.mean <= tolerance.mean && self.p99 <= tolerance.p99
    }
}

/// How much difference a test accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Largest accepted mean error.
    pub mean: f64,
    /// Largest accepted 99th-percentile error.
    pub p99: f64,
}

/// For one scene drawn two ways on one device (techniques, replays, uploads): tight enough to
/// catch a wrong colour on a small part, loose enough for a few edge pixels.
pub const SAME_PICTURE: Tolerance = Tolerance {
    mean: 0.005,
    p99: 0.15,
};

/// For reference images, which other drivers rasterise a little differently on edges.
pub const DEFAULT_TOLERANCE: Tolerance = Tolerance {
    mean: 0.01,
    p99: 0.25,
};

/// A mean error above this is a change a viewer sees (a moved part, a highlight, edges): ten
/// times what two drawings of one picture differ by here, a quarter of the smallest deliberate
/// change.
pub const VISIBLE_CHANGE: f64 = 0.01;

fn rgb_bytes(image: &RgbaImage) -> Vec<u8> {
    // The image crate's own conversion, built optimised: an iterator over the pixels here would
    // run at the tests' opt-level 0, and every comparison of the technique sweeps makes two.
    image::DynamicImage::ImageRgba8(image.clone())
        .to_rgb8()
        .into_raw()
}

/// Compares `test` with `reference` (equal sizes; alpha is ignored).
pub fn compare(test: &RgbaImage, reference: &RgbaImage) -> Result<ImageDifference, String> {
    if test.dimensions() != reference.dimensions() {
        return Err(format!(
            "sizes differ: {:?} vs {:?}",
            test.dimensions(),
            reference.dimensions()
        ));
    }
    let (width, height) = test.dimensions();
    if width == 0 || height == 0 {
        return Ok(SAME);
    }
    let (reference, test) = (rgb_bytes(reference), rgb_bytes(test));
    if reference == test {
        // FLIP of an image against itself is zero at every pixel (the module's test checks it);
        // most comparisons of the technique sweeps are of equal pictures, and FLIP was about a
        // tenth of their time.
        return Ok(SAME);
    }
    flip_difference(width, height, reference, test)
}

/// No difference at all.
const SAME: ImageDifference = ImageDifference {
    mean: 0.0,
    p99: 0.0,
    max: 0.0,
};

/// FLIP's difference of two RGB images of `width` × `height`.
fn flip_difference(
    width: u32,
    height: u32,
    reference: Vec<u8>,
    test: Vec<u8>,
) -> Result<ImageDifference, String> {
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, &reference);
    let test = nv_flip::FlipImageRgb8::with_data(width, height, &test);
    let errors = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&errors);
    Ok(ImageDifference {
        mean: f64::from(pool.mean()),
        p99: f64::from(pool.get_percentile(0.99, false)),
        max: f64::from(pool.max_value()),
    })
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
    if difference.within(tolerance) {
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

/// Whether the pixel at (`x`, `y`) shows the default background (within one step per
/// channel: the GPU rounds the gradient its own way).
pub fn is_background(image: &RgbaImage, x: u32, y: u32) -> bool {
    let expected = Background::default().rgb8_at(y, image.height());
    let pixel = image.get_pixel(x, y).0;
    (0..3).all(|c| pixel[c].abs_diff(expected[c]) <= 1)
}

/// Fraction of pixels that do not show the default background.
pub fn covered_fraction(image: &RgbaImage) -> f64 {
    let covered = image
        .enumerate_pixels()
        .filter(|(x, y, _)| !is_background(image, *x, *y))
        .count();
    covered as f64 / (image.width() * image.height()).max(1) as f64
}

/// The pixel of a `width` × `height` picture drawn through `camera` that the world point
/// `point` projects to.
pub fn pixel_of(
    camera: &cadr_core::render::Camera,
    (width, height): (u32, u32),
    point: glam::DVec3,
) -> (u32, u32) {
    let clip = camera.projection * camera.view * point.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    (
        ((ndc.x + 1.0) * 0.5 * f64::from(width)) as u32,
        ((ndc.y + 1.0) * 0.5 * f64::from(height)) as u32,
    )
}

/// The colour (RGB, 0 to 1) of `image` where the world point `point` shows.
pub fn color_at(
    image: &RgbaImage,
    camera: &cadr_core::render::Camera,
    point: glam::DVec3,
) -> [f32; 3] {
    let (x, y) = pixel_of(camera, image.dimensions(), point);
    let p = image.get_pixel(x, y).0;
    [p[0], p[1], p[2]].map(|c| f32::from(c) / 255.0)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
mod tests {
    use super::*;

    /// The shortcut for equal pictures gives what FLIP itself gives them.
    #[test]
    fn flip_finds_no_difference_between_equal_pictures() {
        let picture = RgbaImage::from_fn(37, 23, |x, y| {
            image::Rgba([(x * 7) as u8, (y * 11) as u8, ((x + y) * 5) as u8, 255])
        });
        let bytes = rgb_bytes(&picture);
        let flipped = flip_difference(37, 23, bytes.clone(), bytes).unwrap();
        // FLIP's pool starts its maximum at the smallest normal float, so an image of zero
        // errors reports that as its largest.
        assert_eq!((flipped.mean, flipped.p99), (0.0, 0.0));
        assert!(flipped.max <= f64::from(f32::MIN_POSITIVE), "{flipped:?}");
        assert_eq!(compare(&picture, &picture.clone()).unwrap(), SAME);
        let mut moved = picture.clone();
        moved.put_pixel(3, 4, image::Rgba([255, 255, 255, 255]));
        assert!(compare(&moved, &picture).unwrap().max > 0.0);
    }
}
