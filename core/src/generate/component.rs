//! One generated CAD component (a geometry): a family of machined shapes whose features are
//! its parts, with about the requested number of parts and triangles per part.

use std::f64::consts::TAU;

use glam::{DMat4, DVec3};

use super::rng::Rng;
use super::shapes::GeometryBuilder;
use crate::scene::Geometry;

/// The shape families components are drawn from.
#[derive(Clone, Copy, Debug)]
enum Family {
    /// A base plate with a grid of bosses.
    PlateWithBosses,
    /// A hub with a ring of bolts and a rim.
    Flange,
    /// A base with a row of thin fins.
    HeatSink,
    /// Turned shaft: stacked sections of changing radius.
    Shaft,
}

const FAMILIES: [Family; 4] = [
    Family::PlateWithBosses,
    Family::Flange,
    Family::HeatSink,
    Family::Shaft,
];

/// Picks the side count of a round feature so that, on average, parts have `triangles_per_part`
/// triangles (a prism with n sides has 4n - 4).
fn round_sides(rng: &mut Rng, triangles_per_part: f64) -> u32 {
    let exact = ((triangles_per_part + 4.0) / 4.0).max(3.0);
    let low = exact.floor();
    let sides = if rng.unit() < exact - low {
        low + 1.0
    } else {
        low
    };
    sides as u32
}

/// Generates a component with `parts` parts (at least 1) of about `triangles_per_part`
/// triangles, within a box of about 1 × 1 × 1 centred on the origin's XZ and resting on y = 0.
pub fn component(name: String, parts: usize, triangles_per_part: f64, rng: &mut Rng) -> Geometry {
    let family = FAMILIES[rng.below(FAMILIES.len())];
    let mut builder = GeometryBuilder::new(format!("{name} ({family:?})"));
    let parts = parts.max(1);
    let sides = |rng: &mut Rng| round_sides(rng, triangles_per_part);
    match family {
        Family::PlateWithBosses => {
            let thickness = rng.range(0.08, 0.16);
            builder.prism(sides(rng), plate(thickness));
            let features = parts - 1;
            let columns = (features as f64).sqrt().ceil().max(1.0) as usize;
            let pitch = 0.8 / columns as f64;
            for i in 0..features {
                let (row, column) = (i / columns, i % columns);
                let height = rng.range(0.1, 0.35);
                let radius = pitch * rng.range(0.25, 0.42);
                let x = -0.4 + pitch * (column as f64 + 0.5);
                let z = -0.4 + pitch * (row as f64 + 0.5);
                builder.prism(
                    sides(rng),
                    upright(DVec3::new(x, thickness, z), radius, height),
                );
            }
        }
        Family::Flange => {
            let hub_height = rng.range(0.2, 0.45);
            builder.prism(sides(rng), upright(DVec3::ZERO, 0.22, hub_height));
            let bolts = parts.saturating_sub(2);
            let plate_thickness = 0.08;
            if parts > 1 {
                builder.prism(sides(rng), upright(DVec3::ZERO, 0.5, plate_thickness));
            }
            for i in 0..bolts {
                let angle = TAU * i as f64 / bolts as f64;
                let ring = if i % 2 == 0 { 0.4 } else { 0.32 };
                let position = DVec3::new(ring * angle.cos(), plate_thickness, ring * angle.sin());
                builder.prism(sides(rng), upright(position, 0.035, rng.range(0.05, 0.1)));
            }
        }
        Family::HeatSink => {
            let base = rng.range(0.06, 0.1);
            builder.cuboid(
                DVec3::new(-0.5, 0.0, -0.35),
                DVec3::new(0.5, base, 0.35),
                DMat4::IDENTITY,
            );
            let fins = parts - 1;
            let pitch = 1.0 / fins.max(1) as f64;
            let height = rng.range(0.25, 0.5);
            for i in 0..fins {
                let x = -0.5 + pitch * (i as f64 + 0.5);
                let half = pitch * 0.2;
                let transform = DMat4::from_translation(DVec3::new(x, base, 0.0));
                // Fins alternate between boxes and faceted rods, so their cost follows the target.
                if i % 2 == 0 {
                    builder.cuboid(
                        DVec3::new(-half, 0.0, -0.33),
                        DVec3::new(half, height, 0.33),
                        transform,
                    );
                } else {
                    builder.prism(
                        sides(rng),
                        transform * rod_along_z(half, 0.66, height * 0.5),
                    );
                }
            }
        }
        Family::Shaft => {
            let section = 1.0 / parts as f64;
            let mut y = 0.0;
            for i in 0..parts {
                let t = i as f64 / parts as f64;
                let radius = 0.12 + 0.1 * (t * TAU * 1.5).sin().abs() + rng.range(0.0, 0.05);
                let length = section * rng.range(0.7, 1.0);
                // Lying along X, its axis high enough that the widest section clears y = 0.
                let transform = DMat4::from_translation(DVec3::new(0.0, 0.3, 0.0))
                    * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2);
                builder.prism(
                    sides(rng),
                    transform * upright(DVec3::new(0.0, -0.5 + y, 0.0), radius, length),
                );
                y += length;
            }
        }
    }
    while builder.part_count() < parts {
        let y = 0.05 * builder.part_count() as f64;
        builder.prism(sides(rng), upright(DVec3::new(0.0, y, 0.0), 0.05, 0.05));
    }
    builder.finish()
}

/// A unit prism scaled to a square-ish plate of `thickness`, resting on y = 0.
fn plate(thickness: f64) -> DMat4 {
    DMat4::from_translation(DVec3::new(0.0, thickness * 0.5, 0.0))
        * DMat4::from_scale(DVec3::new(0.65, thickness, 0.65))
}

/// A unit prism as an upright cylinder of `radius` and `height` standing on `base`.
fn upright(base: DVec3, radius: f64, height: f64) -> DMat4 {
    DMat4::from_translation(base + DVec3::new(0.0, height * 0.5, 0.0))
        * DMat4::from_scale(DVec3::new(radius, height, radius))
}

/// A unit prism as a rod of `radius` and `length` along Z at height `y`.
fn rod_along_z(radius: f64, length: f64, y: f64) -> DMat4 {
    DMat4::from_translation(DVec3::new(0.0, y, 0.0))
        * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2)
        * DMat4::from_scale(DVec3::new(radius, length, radius))
}
