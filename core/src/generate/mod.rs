//! Procedural CAD-like assemblies, so that benchmarks reproduce the seeds' scenes without files.
//!
//! | source | what |
//! |---|---|
//! | `gen:demo` | a small machine room: 160 objects, 12 components, 16 materials |
//! | `gen:graphicscard` | the seeds' "Graphicscard" statistics: ~68 000 parts of ~10 triangles, 2 500 objects, 110 geometries, 66 materials |
//! | `gen:racecar` | ~98 000 parts of ~37 triangles |
//! | `gen:grid:parts=N[,tris=T]` | exactly N parts (T triangles each, default 12) in a cube of objects |
//! | `gen:fine[:units=N,detail=D]` | machined parts with curved faces (flanges, gears, shafts, threaded bolts): 10³–10⁵ triangles per part |
//!
//! Generators are deterministic: the same source gives the same scene on every run.

mod assembly;
mod cabinet;
mod component;
mod fine;
mod grid;
mod rng;
pub(crate) mod shapes;

pub use assembly::{assembly, AssemblySpec};
pub use cabinet::cabinet;
pub use fine::{fine, fine_through};
pub use grid::grid;
pub use rng::Rng;
pub use shapes::{prism_triangles, GeometryBuilder};

use crate::scene::{GeometrySink, Scene};

/// The most parts `gen:grid` generates.
pub const MAX_GRID_PARTS: u64 = 50_000_000;
/// The most triangles per part `gen:grid` generates (its 16 components then hold 16 million
/// triangles, drawn up to 50 million times).
pub const MAX_GRID_TRIANGLES_PER_PART: f64 = 100_000.0;

/// A built-in generator and its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum GeneratorSpec {
    /// `gen:demo`.
    Demo,
    /// `gen:graphicscard`.
    GraphicsCard,
    /// `gen:racecar`.
    RaceCar,
    /// `gen:cabinet[:cabinets=N]`: machines inside closed housings, most parts hidden.
    Cabinet {
        /// Number of cabinets (366 parts each).
        cabinets: u32,
    },
    /// `gen:grid:parts=N[,tris=T]`.
    Grid {
        /// Exact number of parts.
        parts: u64,
        /// Average triangles per part.
        triangles_per_part: f64,
    },
    /// `gen:fine[:units=N,detail=D,unique=1]`: units of machined parts with curved faces, 19
    /// parts each (a flange, a gear, a shaft, eight bolts and their washers, fasteners
    /// instanced).
    Fine {
        /// Number of units.
        units: u32,
        /// Tessellation: about 10³ triangles per part at 1, 10⁵ at 10.
        detail: u32,
        /// Whether every unit has geometries of its own (an assembly of unique parts, as most
        /// CAD assemblies are) instead of sharing four variants.
        unique: bool,
    },
}

/// The most units `gen:fine` makes.
pub const MAX_FINE_UNITS: u32 = 1_000_000;
/// The finest `gen:fine` tessellation.
pub const MAX_FINE_DETAIL: u32 = 32;

/// Host bytes of one unit's geometries in `gen:fine` at detail 1 (vertices and indices of a
/// flange, gear, shaft, bolt and washer, measured, rounded up); they grow with the square of the
/// detail.
const FINE_UNIT_BYTES: u64 = 400_000;

/// Refuses a `gen:fine` of unique units whose geometries would take more than half the
/// machine's physical memory (each unit holds its own: the memory grows with the units).
fn check_unique_fine(units: u32, detail: u32) -> Result<(), String> {
    let bytes = u64::from(units) * u64::from(detail).pow(2) * FINE_UNIT_BYTES;
    let room = crate::memory_budget::physical_memory().map_or(u64::MAX, |m| m / 2);
    if bytes > room {
        return Err(format!(
            "gen:fine: unique=1 with units={units} at detail={detail} would make about {} MB of \
             geometry, more than half this machine's memory ({} MB): fewer units or less detail",
            bytes >> 20,
            room >> 20
        ));
    }
    Ok(())
}

/// The generator names, for help texts.
pub const GENERATOR_NAMES: &str =
    "demo, graphicscard, racecar, cabinet[:cabinets=N], grid:parts=N[,tris=T], fine[:units=N,detail=D,unique=1]";

/// The most cabinets `gen:cabinet` makes (about 11 million parts).
const MAX_CABINETS: u32 = 30_000;

impl GeneratorSpec {
    /// Parses what follows `gen:`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (name, params) = text.split_once(':').unwrap_or((text, ""));
        let params: Vec<(&str, &str)> = params
            .split([',', ':'])
            .filter(|p| !p.is_empty())
            .map(|p| {
                p.split_once('=')
                    .ok_or_else(|| format!("gen:{name}: parameter '{p}' is not KEY=VALUE"))
            })
            .collect::<Result<_, _>>()?;
        let no_params = |spec: Self| match params.first() {
            Some((key, _)) => Err(format!("gen:{name} takes no parameters (got '{key}')")),
            None => Ok(spec),
        };
        match name {
            "demo" => no_params(Self::Demo),
            "graphicscard" => no_params(Self::GraphicsCard),
            "racecar" => no_params(Self::RaceCar),
            "cabinet" => {
                let mut cabinets = 24;
                for (key, value) in params {
                    if key != "cabinets" {
                        return Err(format!(
                            "gen:cabinet: unknown parameter '{key}' (known: cabinets)"
                        ));
                    }
                    cabinets = value
                        .replace('_', "")
                        .parse()
                        .ok()
                        .filter(|n| (1..=MAX_CABINETS).contains(n))
                        .ok_or_else(|| {
                            format!("gen:cabinet: cabinets={value} is not a number from 1 to {MAX_CABINETS}")
                        })?;
                }
                Ok(Self::Cabinet { cabinets })
            }
            "grid" => {
                let mut parts = None;
                let mut triangles_per_part = 12.0;
                for (key, value) in params {
                    match key {
                        "parts" => {
                            let n: u64 = value.replace('_', "").parse().map_err(|_| {
                                format!("gen:grid: parts={value} is not a whole number")
                            })?;
                            if n == 0 || n > MAX_GRID_PARTS {
                                return Err(format!(
                                    "gen:grid: parts={n} is out of range (1 to {MAX_GRID_PARTS})"
                                ));
                            }
                            parts = Some(n);
                        }
                        "tris" => {
                            let t: f64 = value
                                .parse()
                                .map_err(|_| format!("gen:grid: tris={value} is not a number"))?;
                            if !(8.0..=MAX_GRID_TRIANGLES_PER_PART).contains(&t) {
                                return Err(format!(
                                    "gen:grid: tris={t} is out of range (8 to {MAX_GRID_TRIANGLES_PER_PART})"
                                ));
                            }
                            triangles_per_part = t;
                        }
                        other => {
                            return Err(format!(
                                "gen:grid: unknown parameter '{other}' (known: parts, tris)"
                            ))
                        }
                    }
                }
                let parts = parts.ok_or("gen:grid needs parts=N, e.g. gen:grid:parts=100000")?;
                Ok(Self::Grid {
                    parts,
                    triangles_per_part,
                })
            }
            "fine" => {
                let (mut units, mut detail, mut unique) = (16, 2, 0);
                for (key, value) in params {
                    let (target, range) = match key {
                        "units" => (&mut units, 1..=MAX_FINE_UNITS),
                        "detail" => (&mut detail, 1..=MAX_FINE_DETAIL),
                        "unique" => (&mut unique, 0..=1),
                        other => {
                            return Err(format!(
                            "gen:fine: unknown parameter '{other}' (known: units, detail, unique)"
                        ))
                        }
                    };
                    *target = value
                        .replace('_', "")
                        .parse()
                        .ok()
                        .filter(|n| range.contains(n))
                        .ok_or_else(|| {
                            format!(
                                "gen:fine: {key}={value} is not a number from {} to {}",
                                range.start(),
                                range.end()
                            )
                        })?;
                }
                let unique = unique == 1;
                if unique {
                    check_unique_fine(units, detail)?;
                }
                Ok(Self::Fine {
                    units,
                    detail,
                    unique,
                })
            }
            other => Err(format!(
                "unknown generator 'gen:{other}' (known: {GENERATOR_NAMES})"
            )),
        }
    }
}

/// Generates the scene for `spec`.
pub fn generate(spec: &GeneratorSpec) -> Scene {
    generate_through(spec, &mut crate::scene::KeepInScene)
}

/// [`generate`], handing each geometry to `sink` (see [`GeometrySink`]). `gen:fine`, the
/// generator that reaches models larger than memory, hands each as soon as it is made; the
/// others make their (small) scenes whole first.
pub fn generate_through(spec: &GeneratorSpec, sink: &mut dyn GeometrySink) -> Scene {
    if let GeneratorSpec::Fine {
        units,
        detail,
        unique,
    } = spec
    {
        return fine_through(*units, *detail, *unique, sink);
    }
    let mut scene = generate_whole(spec);
    scene.hand_geometries_to(sink);
    scene
}

/// The scene of a generator that makes it whole.
fn generate_whole(spec: &GeneratorSpec) -> Scene {
    match spec {
        GeneratorSpec::Demo => assembly(&AssemblySpec {
            name: "demo".into(),
            objects: 160,
            geometries: 12,
            materials: 16,
            parts_per_geometry: 9.0,
            triangles_per_part: 28.0,
            objects_per_module: 40,
            seed: 7,
        }),
        GeneratorSpec::GraphicsCard => assembly(&AssemblySpec {
            name: "graphicscard".into(),
            objects: 2497,
            geometries: 110,
            materials: 66,
            parts_per_geometry: 27.4,
            triangles_per_part: 10.0,
            objects_per_module: 50,
            seed: 2014,
        }),
        // Machine beds and boxy features have 12 triangles; round features are tuned up so
        // that parts average the seed's 37.
        GeneratorSpec::RaceCar => assembly(&AssemblySpec {
            name: "racecar".into(),
            objects: 3500,
            geometries: 180,
            materials: 80,
            parts_per_geometry: 28.0,
            triangles_per_part: 40.5,
            objects_per_module: 60,
            seed: 2015,
        }),
        GeneratorSpec::Cabinet { cabinets } => cabinet(*cabinets),
        GeneratorSpec::Grid {
            parts,
            triangles_per_part,
        } => grid(*parts, *triangles_per_part),
        GeneratorSpec::Fine {
            units,
            detail,
            unique,
        } => fine(*units, *detail, *unique),
    }
}
