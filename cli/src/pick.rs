//! `cadr pick SCENE X Y [--size WxH] [--rect X2,Y2] [technique options] [--json]`: what lies
//! under a pixel (or the parts with visible pixels in a rectangle) of the view `render` draws,
//! picked by the pick pass of the chosen techniques.

use cadr_core::graph::{NodeHandle, SceneGraph};
use cadr_core::render::pick::PixelRect;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, SceneStats};
use cadr_core::view::PickHit;

use crate::args::{parse_size, Args};
use crate::techniques::{self, TechniqueSession};

/// The options `pick` takes besides the technique options.
const OPTIONS: &[&str] = &[
    "--size",
    "--rect",
    "--json",
    "--validation",
    "--no-validation",
    "--vertex",
    "--params",
    "--submit",
    "--cull",
    "--shade",
    "--min-pixels",
];

fn coordinate(text: &str, what: &str) -> Result<u32, String> {
    text.trim()
        .parse::<u32>()
        .map_err(|_| format!("{what} '{text}': expected a pixel coordinate (0 or more)"))
}

/// A node as the user knows it: its name, or `#slot` when it has none.
fn node_label(graph: &SceneGraph, node: NodeHandle) -> String {
    match graph.node(node) {
        Ok(n) if !n.name.is_empty() => n.name.clone(),
        _ => format!("#{}", node.index()),
    }
}

fn hit_json(graph: &SceneGraph, hit: &PickHit) -> serde_json::Value {
    serde_json::json!({
        "node": node_label(graph, hit.node),
        "node_id": hit.node.index(),
        "part": hit.part,
        "path": hit.path.iter().map(|&n| node_label(graph, n)).collect::<Vec<_>>(),
        "path_ids": hit.path.iter().map(|n| n.index()).collect::<Vec<_>>(),
        "pixel": [hit.pixel.0, hit.pixel.1],
        "depth": hit.depth,
        "position": hit.position.to_array(),
    })
}

fn hit_line(graph: &SceneGraph, hit: &PickHit) -> String {
    let path: Vec<String> = hit.path.iter().map(|&n| node_label(graph, n)).collect();
    format!(
        "{} part {} at pixel ({}, {}), depth {:.6}, world ({:.6}, {:.6}, {:.6})\n    path: {}",
        node_label(graph, hit.node),
        hit.part,
        hit.pixel.0,
        hit.pixel.1,
        hit.depth,
        hit.position.x,
        hit.position.y,
        hit.position.z,
        path.join(" / ")
    )
}

/// `cadr pick`.
pub fn pick(args: &Args) -> Result<(), String> {
    args.reject_unknown("pick", OPTIONS)?;
    let (scene_text, x, y) = match args.positionals() {
        [scene, x, y] => (scene.as_str(), coordinate(x, "X")?, coordinate(y, "Y")?),
        [_, _, _, extra, ..] => return Err(format!("cadr pick: unexpected argument '{extra}'")),
        _ => return Err("cadr pick: expected SCENE X Y (see cadr --help)".into()),
    };
    let (width, height) = parse_size(args.value(&["--size"]).unwrap_or("1024x768"))?;
    let rect = match args.value(&["--rect"]) {
        None => PixelRect::pixel(x, y),
        Some(text) => {
            let (x2, y2) = text
                .split_once(',')
                .ok_or_else(|| format!("--rect {text}: expected X2,Y2 (the other corner)"))?;
            PixelRect::spanning(
                (x, y),
                (coordinate(x2, "--rect X2")?, coordinate(y2, "--rect Y2")?),
            )
        }
    };
    if u64::from(rect.x) + u64::from(rect.width) > u64::from(width)
        || u64::from(rect.y) + u64::from(rect.height) > u64::from(height)
    {
        return Err(format!(
            "pixels {rect} are outside the {width}x{height} view (--size)"
        ));
    }
    let (combination, shade) = techniques::combination_from_args(args)?;
    let min_pixels = techniques::min_pixels_from_args(args)?;
    let source = cadr_core::load::SceneSource::parse(scene_text).map_err(|e| e.to_string())?;
    let scene = source.load().map_err(|e| e.to_string())?;
    let flat = flatten(&scene).map_err(|e| e.to_string())?;
    let stats = SceneStats::new(&scene, &flat);
    drop(flat);
    let device = crate::open_device(args)?;
    let (registry, _) = techniques::load_registry(&device);
    let mut session = TechniqueSession::new(&device, &scene, registry, (width, height))?;
    session.choose(&combination, shade)?;
    session.set_min_pixels(min_pixels)?;
    // The view `cadr render` draws: the camera fitted to the scene's bounds.
    let camera = Camera::fit(
        &stats.bounds,
        f64::from(width) / f64::from(height),
        DEFAULT_DIRECTION,
    );
    let hits = session
        .view
        .pick(&session.graph, &mut session.tree, &camera, rect)
        .map_err(|e| e.to_string())?;
    let validation_errors = device.validation_log().errors().len();
    if validation_errors > 0 {
        return Err(format!(
            "{validation_errors} Vulkan validation errors (see above)"
        ));
    }
    let graph = &session.graph;
    let single = rect.width == 1 && rect.height == 1;
    if args.flag("--json") {
        let mut report = serde_json::json!({
            "hit": !hits.is_empty(),
            "pixel": [x, y],
            "size": [width, height],
            "techniques": combination.to_string(),
        });
        if single {
            if let (Some(hit), Some(object)) = (hits.first(), report.as_object_mut()) {
                if let serde_json::Value::Object(fields) = hit_json(graph, hit) {
                    object.extend(fields);
                }
            }
        } else if let Some(object) = report.as_object_mut() {
            object.insert(
                "rect".into(),
                serde_json::json!([rect.x, rect.y, rect.width, rect.height]),
            );
            object.insert(
                "hits".into(),
                hits.iter().map(|h| hit_json(graph, h)).collect(),
            );
        }
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    if hits.is_empty() {
        println!("nothing pickable at {rect} ({width}x{height} view)");
    } else if single {
        println!("hit: {}", hit_line(graph, &hits[0]));
    } else {
        println!("{} parts with visible pixels in {rect}:", hits.len());
        for hit in &hits {
            println!("  {}", hit_line(graph, hit));
        }
    }
    Ok(())
}
