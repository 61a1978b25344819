//! `cadr bench`'s sweeps: the CPU cost of a technique set over gen:grid of growing part
//! counts (`--sweep`), and the GPU cost of per-part and cluster culling over gen:fine of
//! growing tessellation (`--sweep-detail`), each with its table, JSON and plot.

use cadr_core::scene::SceneStats;
use cadr_core::technique::Combination;

use crate::args::BenchArgs;
use crate::bench::{row_mode, rows_json, section_json, stats_json, Bench, Row, SWEEP_SET};

/// Measures `combinations` (and the baseline, `with_baseline`) on each scene of `scenes`
/// (`(key, source)` pairs): per scene its key, statistics and rows.
fn measure_scenes<K>(
    bench: &Bench,
    args: &BenchArgs,
    scenes: impl Iterator<Item = (K, String)>,
    combinations: &[Combination],
    with_baseline: bool,
) -> Result<Vec<(K, SceneStats, Vec<Row>)>, String> {
    scenes
        .map(|(key, source)| {
            println!("measuring {source} ...");
            let (stats, rows) =
                bench.run(&source, Some(combinations), args, (true, with_baseline))?;
            Ok((key, stats, rows))
        })
        .collect()
}

/// Measures the sweep set over gen:grid scenes of growing size.
pub(crate) fn run_sweep(bench: &Bench, args: &BenchArgs) -> Result<serde_json::Value, String> {
    let parts: Vec<u64> = args
        .sweep_parts
        .clone()
        .unwrap_or_else(|| vec![10_000, 100_000, 1_000_000]);
    let combinations: Vec<Combination> = SWEEP_SET
        .iter()
        .map(|&(vertex, parameters, submission)| Combination {
            vertex: vertex.into(),
            parameters: parameters.into(),
            submission: submission.into(),
            culling: "none".into(),
            ..Combination::built_in()
        })
        .collect();
    let scenes = parts.iter().map(|&n| (n, format!("gen:grid:parts={n}")));
    let columns = measure_scenes(bench, args, scenes, &combinations, true)?;
    let Some((_, _, first_rows)) = columns.first() else {
        return Err("no sweep sizes".into());
    };
    print!(
        "{:<58}",
        "CPU µs per frame (vertex / params / submit / cull)"
    );
    for (n, _, _) in &columns {
        print!(" {:>12}", format!("{n} parts"));
    }
    println!(" {:>10}", "last/first");
    for (i, row) in first_rows.iter().enumerate() {
        print!("{:<58}", format!("{} [{}]", row.label, row_mode(row)));
        for (_, _, rows) in &columns {
            print!(" {:>12.1}", rows[i].cpu_us);
        }
        let (first, last) = (
            columns[0].2[i].cpu_us,
            columns[columns.len() - 1].2[i].cpu_us,
        );
        println!(" {:>9.2}x", last / first.max(0.001));
    }
    if let Some(path) = &args.plot {
        let series: Vec<crate::plot::Series> = first_rows
            .iter()
            .enumerate()
            .map(|(i, row)| crate::plot::Series {
                label: format!("{} [{}]", row.label, row_mode(row)),
                points: columns
                    .iter()
                    .map(|(n, _, rows)| (*n, rows[i].cpu_us))
                    .collect(),
            })
            .collect();
        let title = format!(
            "gen:grid sweep on {} — CPU µs per frame",
            bench.device.adapter().name
        );
        crate::plot::lines(path, &title, ("parts", "CPU µs per frame"), &series)?;
        println!("wrote {}", path.display());
    }
    let sizes: Vec<serde_json::Value> = columns
        .iter()
        .map(|(n, stats, rows)| {
            serde_json::json!({
                "parts": n,
                "scene": stats_json(&format!("gen:grid:parts={n}"), stats),
                "rows": rows_json(rows),
            })
        })
        .collect();
    Ok(serde_json::json!({
        "device": bench.device.adapter().name,
        "frames": bench.frames,
        "section": section_json(&bench.section),
        "sweep": sizes,
    }))
}

/// The culling rows of the detail sweep: per-part occlusion, then clusters at full detail and
/// at each `--lod-error`; their commands drawn with the count the GPU wrote, or by their
/// capacity on a device without `drawIndirectCount` (`has_indirect_count` false).
fn detail_combinations(has_indirect_count: bool) -> Vec<Combination> {
    let submission = if has_indirect_count {
        "individual-indirect-count"
    } else {
        "individual-mdi"
    };
    ["gpu-occlusion", "gpu-clusters"]
        .iter()
        .map(|culling| Combination {
            vertex: "arena".into(),
            parameters: "ssbo-index".into(),
            submission: submission.into(),
            culling: (*culling).into(),
            ..Combination::built_in()
        })
        .collect()
}

/// Measures per-part and cluster culling over gen:fine of growing tessellation (scene
/// triangles at a fixed resolution): GPU µs and triangles rasterised per frame.
pub(crate) fn run_detail_sweep(
    bench: &Bench,
    args: &BenchArgs,
    details: &[u32],
) -> Result<serde_json::Value, String> {
    let combinations = detail_combinations(bench.device.capabilities().draw_indirect_count);
    let scenes = details.iter().map(|&detail| {
        let name = format!("gen:fine:units={},detail={detail}", args.sweep_units);
        (name.clone(), name)
    });
    // The GPU rows are the subject: the baseline's CPU reference is left out.
    let columns = measure_scenes(bench, args, scenes, &combinations, false)?;
    let Some((_, _, first_rows)) = columns.first() else {
        return Err("no sweep details".into());
    };
    println!(
        "{:<58} {:>14} {:>14} {:>14}",
        "GPU µs per frame / triangles rasterised", "scene tris", "GPU µs", "rasterised"
    );
    for (i, row) in first_rows.iter().enumerate() {
        for (name, stats, rows) in &columns {
            let r = &rows[i];
            println!(
                "{:<58} {:>14} {:>14} {:>14}",
                format!("{} [{}] {}", row.label, row_mode(row), name),
                stats.triangles,
                r.gpu_us.map_or("n/a".to_owned(), |g| format!("{g:.0}")),
                r.stats.triangles_rasterized
            );
        }
        let gpu = |rows: &[Row]| rows[i].gpu_us.unwrap_or(f64::NAN);
        let (first, last) = (gpu(&columns[0].2), gpu(&columns[columns.len() - 1].2));
        println!(
            "{:<58} GPU last/first {:.2}x",
            format!("{} [{}]", row.label, row_mode(row)),
            last / first
        );
    }
    if let Some(path) = &args.plot {
        let series: Vec<crate::plot::Series> = first_rows
            .iter()
            .enumerate()
            .map(|(i, row)| crate::plot::Series {
                label: format!("{} [{}]", row.label, row_mode(row)),
                points: columns
                    .iter()
                    .map(|(_, stats, rows)| (stats.triangles, rows[i].gpu_us.unwrap_or(0.0)))
                    .collect(),
            })
            .collect();
        let title = format!(
            "gen:fine sweep on {} — GPU µs per frame over scene triangles",
            bench.device.adapter().name
        );
        crate::plot::lines(
            path,
            &title,
            ("scene triangles", "GPU µs per frame"),
            &series,
        )?;
        println!("wrote {}", path.display());
    }
    let sizes: Vec<serde_json::Value> = columns
        .iter()
        .map(|(name, stats, rows)| {
            serde_json::json!({
                "scene": stats_json(name, stats),
                "rows": rows_json(rows),
            })
        })
        .collect();
    Ok(serde_json::json!({
        "device": bench.device.adapter().name,
        "frames": bench.frames,
        "section": section_json(&bench.section),
        "detail_sweep": sizes,
    }))
}
