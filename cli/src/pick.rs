//! `cadr pick SCENE X Y [--size WxH] [--rect X2,Y2] [technique options] [--json]`: what lies
//! under a pixel (or the parts with visible pixels in a rectangle) of the view `render` draws,
//! picked by the pick pass of the chosen techniques.

use cadr_core::graph::{NodeHandle, SceneGraph};
use cadr_core::render::pick::PixelRect;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::view::PickHit;

use crate::args::{PickArgs, Size};
use crate::techniques::{self, TechniqueSession};

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
pub fn pick(args: &PickArgs) -> Result<(), String> {
    let (x, y) = (args.x, args.y);
    let Size { width, height } = args.size;
    let rect = match args.rect {
        None => PixelRect::pixel(x, y),
        Some(corner) => PixelRect::spanning((x, y), corner),
    };
    if u64::from(rect.x) + u64::from(rect.width) > u64::from(width)
        || u64::from(rect.y) + u64::from(rect.height) > u64::from(height)
    {
        return Err(format!(
            "pixels {rect} are outside the {width}x{height} view (--size)"
        ));
    }
    let combination = args.techniques.combination();
    let shade = args.techniques.shade_mode();
    let min_pixels = args.techniques.min_pixels();
    let section = args.section.section()?;
    let crate::LoadedGraph { graph, stats, .. } = crate::load_graph(&args.scene, &[])?;
    let device = crate::open_device(&args.validation)?;
    let (registry, _) = techniques::load_registry(&device);
    let mut session = TechniqueSession::from_graph(&device, graph, registry, (width, height))?;
    session.choose(&combination, shade)?;
    session.set_min_pixels(min_pixels)?;
    session.set_lod_error(args.techniques.lod_error)?;
    session.set_section(section);
    session
        .techniques()
        .set_pick_through_translucent(args.through_translucent);
    // The view `cadr render` draws: the camera fitted to the scene's bounds.
    let camera = Camera::fit(
        &stats.bounds,
        f64::from(width) / f64::from(height),
        DEFAULT_DIRECTION,
    );
    session
        .view
        .sync(&session.graph, &mut session.tree)
        .map_err(|e| e.to_string())?;
    let hits = session
        .view
        .pick(&session.tree, &camera, rect)
        .map_err(|e| e.to_string())?;
    let validation_errors = device.validation_log().errors().len();
    if validation_errors > 0 {
        return Err(format!(
            "{validation_errors} Vulkan validation errors (see above)"
        ));
    }
    let graph = &session.graph;
    let single = rect.width == 1 && rect.height == 1;
    if args.json {
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
