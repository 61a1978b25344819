//! Geometry streaming under a memory budget (`CADR_MEMORY_BUDGET`, in a test binary of its own,
//! as it sets the process's environment): a scene whose full detail needs several times the
//! budget draws every part from the first frame (coarse forms), never holds more full detail
//! than the budget, and converges to the full-detail picture where the view needs less.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::gpu_scene::StreamingReport;
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Aabb, Scene, VertexAttributes};
use cadr_core::technique::ShadeMode;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, covered_fraction};
use cadr_tests::{assert_no_validation_errors, gpu_culled, plugin_registry, test_device};
use glam::DVec3;

/// Units of the scene: each with geometries of its own.
const UNITS: u32 = 16;
/// The budget is this fraction of the scene's full detail.
const BUDGET_SHARE: u64 = 6;
/// Frames a still view may take to reach full detail: the full detail is prepared on a thread
/// of its own while frames go on, so how many depends on the machine's load.
const CONVERGENCE_FRAMES: usize = 80;
const SIZE: (u32, u32) = (240, 180);

/// gen:fine with every unit's parts geometries of their own (a CAD assembly of unique parts,
/// which is what streaming works on: a geometry is at full detail or not).
fn unique_parts() -> Scene {
    generate(&GeneratorSpec::Fine {
        units: UNITS,
        detail: 2,
        unique: true,
    })
}

/// The whole scene, fitted in the default direction.
fn fitted_view(scene: &Scene) -> Camera {
    let bounds = flatten(scene).unwrap().bounds;
    Camera::fit(
        &bounds,
        f64::from(SIZE.0) / f64::from(SIZE.1),
        DEFAULT_DIRECTION,
    )
}

/// Looks at the first unit from up close, turned by `turn` radians around it.
fn close_up(turn: f64) -> Camera {
    close_up_at(DVec3::ZERO, turn)
}

/// Looks from up close at the unit whose origin is `centre`, turned by `turn` radians around it.
fn close_up_at(centre: DVec3, turn: f64) -> Camera {
    let unit = Aabb {
        min: centre - DVec3::splat(0.5),
        max: centre + DVec3::splat(0.5),
    };
    let direction = DVec3::new(turn.sin(), -0.6, turn.cos()).normalize();
    Camera::fit(&unit, f64::from(SIZE.0) / f64::from(SIZE.1), direction)
}

/// A view of `scene` on the test device, under `budget`, drawn with `culler` (scene-wide
/// techniques; `gpu-clusters` at 1 px) or the built-in combination (`None`).
struct Session {
    device: Arc<cadr_core::vk::Device>,
    graph: SceneGraph,
    tree: SceneTree,
    view: View,
}

fn session(scene: &Scene, budget: Option<u64>, culler: Option<&str>) -> Session {
    session_with(scene, budget, culler, None)
}

/// [`session`], with the graph keeping at most `memory_limit` bytes of geometry in memory
/// (the rest in its page file) where given, else half the budget.
fn session_with(
    scene: &Scene,
    budget: Option<u64>,
    culler: Option<&str>,
    memory_limit: Option<u64>,
) -> Session {
    // SAFETY of the environment: this test binary runs one test at a time (nextest: one per
    // process), and reads the variable only when the scene is put on the GPU.
    match budget {
        Some(bytes) => std::env::set_var("CADR_MEMORY_BUDGET", bytes.to_string()),
        None => std::env::remove_var("CADR_MEMORY_BUDGET"),
    }
    let device = test_device();
    let mut graph = SceneGraph::new();
    if let Some(limit) = memory_limit {
        graph.set_geometry_memory_limit(limit);
    }
    graph.import(scene, graph.root()).unwrap();
    let tree = SceneTree::build(&mut graph);
    let mut view = View::new(
        &device,
        Arc::clone(&plugin_registry(&device)),
        SIZE.0,
        SIZE.1,
    )
    .unwrap();
    if let Some(culler) = culler {
        let combination = gpu_culled(&device, culler);
        view.techniques_mut().select(&combination).unwrap();
        if culler == "gpu-clusters" {
            view.techniques_mut().set_lod_error(1.0).unwrap();
        }
    }
    Session {
        device,
        graph,
        tree,
        view,
    }
}

/// Renders `cameras` one frame each (at 1 px, gpu-clusters) with `budget`; returns the pictures
/// and the streaming report after each.
fn render(
    scene: &Scene,
    budget: Option<u64>,
    cameras: &[Camera],
) -> (Vec<image::RgbaImage>, Vec<Option<StreamingReport>>, u64) {
    render_with(scene, budget, cameras, Some("gpu-clusters"), &|_| false)
}

/// [`render`] with `culler` (scene-wide techniques), or the built-in combination (`None`),
/// stopping early after a picture `done` accepts.
fn render_with(
    scene: &Scene,
    budget: Option<u64>,
    cameras: &[Camera],
    culler: Option<&str>,
    done: &dyn Fn(&image::RgbaImage) -> bool,
) -> (Vec<image::RgbaImage>, Vec<Option<StreamingReport>>, u64) {
    let Session {
        device,
        graph,
        mut tree,
        mut view,
    } = session(scene, budget, culler);
    let mut images = Vec::new();
    let mut reports = Vec::new();
    let mut resident = 0;
    for camera in cameras {
        view.render(&graph, &mut tree, camera).unwrap();
        images.push(view.renderer().read_rgba8().unwrap());
        let scene = view.scene().unwrap();
        reports.push(scene.streaming());
        resident = resident.max(scene.resident_bytes());
        drop(scene);
        if done(images.last().unwrap()) {
            break;
        }
    }
    drop(view);
    assert_no_validation_errors(&device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
    (images, reports, resident)
}

#[test]
fn a_scene_over_the_budget_streams_its_full_detail_where_the_view_needs_it() {
    let scene = unique_parts();
    let still = vec![close_up(0.0); CONVERGENCE_FRAMES];
    let (full, none, full_resident) = render(&scene, None, &still[..1]);
    assert_eq!(none[0], None, "a scene within the budget does not stream");
    let reference = &full[0];

    // Find the scene's full-detail bytes from a first streaming run, then set the budget.
    let (_, probe, _) = render(&scene, Some(1 << 20), &still[..1]);
    let total = probe[0].unwrap().total_full_bytes;
    let budget = total / BUDGET_SHARE;
    let full_detail = |image: &image::RgbaImage| compare(image, reference).unwrap().mean <= 1e-4;
    let (images, reports, resident) = render_with(
        &scene,
        Some(budget),
        &still,
        Some("gpu-clusters"),
        &full_detail,
    );
    let reports: Vec<StreamingReport> = reports.into_iter().map(Option::unwrap).collect();
    for report in &reports {
        assert_eq!(report.budget, budget);
        assert!(
            report.full_bytes <= budget,
            "full detail within the budget: {report:?}"
        );
    }
    // The first frame draws the coarse forms: every part there, none at full detail yet.
    let first = compare(&images[0], reference).unwrap();
    assert!(first.mean > 0.0, "the first frame is coarse: {first:?}");
    let (covered, covered_full) = (covered_fraction(&images[0]), covered_fraction(reference));
    assert!(
        (covered - covered_full).abs() < 0.01,
        "no part missing while coarse: {covered} of the picture covered against {covered_full}"
    );
    // Full detail reached: the picture the unbudgeted scene draws (up to rounding).
    let converged = (images.iter())
        .position(|image| compare(image, reference).unwrap().mean <= 1e-4)
        .unwrap_or_else(|| {
            panic!(
                "no frame reached full detail: last {:?}, streaming {:?}",
                compare(images.last().unwrap(), reference).unwrap(),
                reports.last()
            )
        });
    let last = compare(images.last().unwrap(), reference).unwrap();
    println!(
        "full detail {total} bytes, budget {budget}; the picture of full detail after {converged} \
         frames (first {first:?}, last {last:?}); resident {resident} bytes against \
         {full_resident} unbudgeted; {:?}",
        reports.last()
    );
    assert!(converged > 0 && last.mean <= 1e-4, "{last:?}");
    assert!(reports.last().unwrap().streamed_bytes > 0);
    assert!(
        resident < full_resident / 2,
        "the GPU scene holds {resident} bytes against {full_resident} without a budget"
    );
}

#[test]
fn an_orbit_under_the_budget_never_shows_a_hole() {
    let scene = unique_parts();
    let orbit: Vec<Camera> = (0..10).map(|i| close_up(f64::from(i) * 0.6)).collect();
    let (full, _, _) = render(&scene, None, &orbit);
    let (_, probe, _) = render(&scene, Some(1 << 20), &orbit[..1]);
    let budget = probe[0].unwrap().total_full_bytes / BUDGET_SHARE;
    let (images, reports, _) = render(&scene, Some(budget), &orbit);
    for (frame, (image, reference)) in images.iter().zip(&full).enumerate() {
        let (covered, covered_full) = (covered_fraction(image), covered_fraction(reference));
        assert!(
            (covered - covered_full).abs() < 0.01,
            "frame {frame}: {covered} of the picture covered against {covered_full} at full detail"
        );
        let report = reports[frame].unwrap();
        assert!(report.full_bytes <= budget, "{report:?}");
    }
    // Asked for (its bytes held for it): when it arrives depends on the preparing thread.
    let asked = reports.last().unwrap().unwrap().full_bytes;
    assert!(asked > 0, "the orbit asked for full detail: {reports:?}");
}

#[test]
fn cullers_without_a_threshold_ask_for_what_they_draw() {
    let scene = unique_parts();
    let still = vec![close_up(0.0); CONVERGENCE_FRAMES];
    let (_, probe, _) = render(&scene, Some(1 << 20), &still[..1]);
    let budget = probe[0].unwrap().total_full_bytes / BUDGET_SHARE;
    // The built-in combination (CPU, no culling), a CPU frustum culler and a GPU one without a
    // threshold: each draws full detail, so each asks for the geometries it draws.
    for culler in [None, Some("frustum"), Some("gpu-occlusion")] {
        let (reference, _, _) = render_with(&scene, None, &still[..1], culler, &|_| false);
        let full_detail =
            |image: &image::RgbaImage| compare(image, &reference[0]).unwrap().mean <= 1e-4;
        let (images, reports, _) = render_with(&scene, Some(budget), &still, culler, &full_detail);
        let report = reports.last().unwrap().unwrap();
        let first = compare(&images[0], &reference[0]).unwrap();
        let last = compare(images.last().unwrap(), &reference[0]).unwrap();
        println!("{culler:?}: first {first:?}, last {last:?}, {report:?}");
        assert!(first.mean > 0.0, "{culler:?}: the first frame is coarse");
        assert!(
            report.streamed_bytes > 0 && report.full_bytes <= budget,
            "{report:?}"
        );
        assert!(
            last.mean <= 1e-4,
            "{culler:?}: the close-up reaches full detail where it fits: {last:?}, {report:?}"
        );
    }
}

#[test]
fn the_whole_scene_under_the_budget_stays_within_the_fidelity_goal() {
    let scene = unique_parts();
    let fitted = fitted_view(&scene);
    let frames = vec![fitted; 4];
    let (full, _, _) = render(&scene, None, &frames[..1]);
    let (_, probe, _) = render(&scene, Some(1 << 20), &frames[..1]);
    let budget = probe[0].unwrap().total_full_bytes / BUDGET_SHARE;
    let (images, reports, _) = render(&scene, Some(budget), &frames);
    let difference = compare(images.last().unwrap(), &full[0]).unwrap();
    println!("fitted view: {difference:?}, {:?}", reports.last());
    assert!(difference.mean <= 0.02, "{difference:?}");
    let (covered, covered_full) = (
        covered_fraction(images.last().unwrap()),
        covered_fraction(&full[0]),
    );
    assert!(
        (covered - covered_full).abs() < 0.01,
        "{covered} against {covered_full}"
    );
}

#[test]
fn a_view_that_needs_more_than_the_budget_does_not_swap_geometries_back_and_forth() {
    let scene = unique_parts();
    let still = vec![close_up(0.0); 30];
    let (_, probe, _) = render(&scene, Some(1 << 20), &still[..1]);
    // Room for about one of the close-up's geometries at full detail.
    let budget = probe[0].unwrap().total_full_bytes / 60;
    let (_, reports, _) = render(&scene, Some(budget), &still);
    let last = reports.last().unwrap().unwrap();
    println!("{last:?}");
    for report in reports.iter().flatten() {
        assert!(report.full_bytes <= budget, "{report:?}");
    }
    assert!(last.streamed_bytes > 0, "{last:?}");
    assert!(
        last.streamed_bytes <= budget,
        "what came stays while the view wants it: {last:?}"
    );
}

#[test]
fn a_geometry_replaced_while_the_scene_streams_is_drawn_as_its_new_data() {
    let scene = unique_parts();
    let budget = {
        let (_, probe, _) = render(&scene, Some(1 << 20), &[close_up(0.0)]);
        probe[0].unwrap().total_full_bytes / BUDGET_SHARE
    };
    // The first unit's flange, tessellated finer: its room is too small, and the arenas are
    // laid out again while full detail is on its way.
    let finer = generate(&GeneratorSpec::Fine {
        units: 1,
        detail: 4,
        unique: true,
    });
    let flange_slot = 2;
    let finer_flange = finer.geometries[flange_slot].clone();
    let draw = |budget: Option<u64>| {
        let Session {
            device,
            mut graph,
            mut tree,
            mut view,
        } = session(&scene, budget, Some("gpu-occlusion"));
        let camera = close_up(0.0);
        for _ in 0..2 {
            view.render(&graph, &mut tree, &camera).unwrap();
        }
        let handle = graph.geometry_handle_at(flange_slot as u32).unwrap();
        graph
            .replace_geometry(handle, finer_flange.clone())
            .unwrap();
        tree.update(&mut graph);
        let mut images = Vec::new();
        for _ in 0..CONVERGENCE_FRAMES {
            view.render(&graph, &mut tree, &camera).unwrap();
            images.push(view.renderer().read_rgba8().unwrap());
            if budget.is_none() {
                break;
            }
        }
        let report = view.scene().unwrap().streaming();
        drop(view);
        assert_no_validation_errors(&device);
        std::env::remove_var("CADR_MEMORY_BUDGET");
        (images, report)
    };
    let (reference, _) = draw(None);
    let (images, report) = draw(Some(budget));
    let report = report.unwrap();
    assert!(report.full_bytes <= budget, "{report:?}");
    let differences: Vec<f64> = (images.iter())
        .map(|image| compare(image, &reference[0]).unwrap().mean)
        .collect();
    println!("{report:?}; FLIP per frame after the edit: {differences:?}");
    assert!(
        differences.iter().any(|&mean| mean <= 1e-4),
        "the new flange at full detail, as drawn without a budget: {differences:?}"
    );
}

#[test]
fn a_page_file_that_cannot_be_read_keeps_the_coarse_form_until_a_retry_reads_it() {
    let scene = unique_parts();
    let still = vec![close_up(0.0); CONVERGENCE_FRAMES];
    let (full, _, _) = render(&scene, None, &still[..1]);
    let reference = &full[0];
    let (_, probe, _) = render(&scene, Some(1 << 20), &still[..1]);
    let budget = probe[0].unwrap().total_full_bytes / BUDGET_SHARE;
    // The graph keeps every geometry in its page file.
    let Session {
        device,
        graph,
        mut tree,
        mut view,
    } = session_with(&scene, Some(budget), Some("gpu-clusters"), Some(0));
    let memory = graph.geometry_memory();
    println!("{memory:?}");
    assert!(
        memory.paged_geometries as usize == scene.geometries.len() && memory.resident_bytes == 0
    );
    let page_file = memory.page_file.clone().unwrap();
    let pages = std::fs::read(&page_file).unwrap();
    assert_eq!(pages.len() as u64, memory.paged_bytes);
    // The first frame lays the scene out (reading every page) and draws the coarse forms.
    view.render(&graph, &mut tree, &still[0]).unwrap();

    // The file is cut short under the scene (a full disk, another program): reading fails.
    std::fs::File::options()
        .write(true)
        .open(&page_file)
        .unwrap()
        .set_len(0)
        .unwrap();
    let paged = (0..scene.geometries.len() as u32)
        .find(|&slot| graph.geometry_info_at(slot).unwrap().paged)
        .unwrap();
    let error = graph.geometry_at(paged).unwrap_err().to_string();
    assert!(
        error.contains(&scene.geometries[paged as usize].name)
            && error.contains(&page_file.display().to_string()),
        "the error names the geometry and the file: {error}"
    );
    let mut failed_reads = 0;
    for camera in &still {
        view.render(&graph, &mut tree, camera).unwrap();
        let image = view.renderer().read_rgba8().unwrap();
        let (covered, covered_full) = (covered_fraction(&image), covered_fraction(reference));
        assert!(
            (covered - covered_full).abs() < 0.01,
            "no hole while reads fail: {covered} covered against {covered_full}"
        );
        failed_reads = view.scene().unwrap().streaming().unwrap().failed_reads;
        if failed_reads > 0 {
            break;
        }
    }
    assert!(failed_reads > 0, "the failed reads are counted");

    // The file is whole again: the geometries are read again and reach full detail.
    std::fs::write(&page_file, &pages).unwrap();
    let mut converged = None;
    for (frame, camera) in still.iter().enumerate() {
        view.render(&graph, &mut tree, camera).unwrap();
        let image = view.renderer().read_rgba8().unwrap();
        if compare(&image, reference).unwrap().mean <= 1e-4 {
            converged = Some(frame);
            break;
        }
    }
    let report = view.scene().unwrap().streaming().unwrap();
    println!("{failed_reads} failed reads; full detail {converged:?} frames after the repair; {report:?}");
    assert!(
        converged.is_some(),
        "a retry reads the repaired file: {report:?}"
    );
    drop(view);
    assert_no_validation_errors(&device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
}

/// Draws `camera` in `session` until two frames in a row are the same and differ from the
/// first (`coarse`); returns whether that happened within [`CONVERGENCE_FRAMES`].
fn draw_until_full_detail(
    session: &mut Session,
    camera: &Camera,
    coarse: &image::RgbaImage,
) -> bool {
    let mut last: Option<image::RgbaImage> = None;
    for _ in 0..CONVERGENCE_FRAMES {
        let image = draw(session, camera).0;
        if let Some(last) = &last {
            if compare(last, &image).unwrap().mean == 0.0
                && compare(&image, coarse).unwrap().mean > 0.0
            {
                return true;
            }
        }
        last = Some(image);
    }
    false
}

/// Draws one frame of `camera` in `session`; returns the picture and the streaming report.
fn draw(session: &mut Session, camera: &Camera) -> (image::RgbaImage, StreamingReport) {
    let Session {
        graph, tree, view, ..
    } = session;
    view.render(graph, tree, camera).unwrap();
    let image = view.renderer().read_rgba8().unwrap();
    let report = view.scene().unwrap().streaming().unwrap();
    (image, report)
}

#[test]
fn a_geometry_put_back_in_its_coarse_form_draws_it_as_it_first_did() {
    let scene = unique_parts();
    let unit = |name: &str| {
        let node = scene.nodes.iter().find(|n| n.name == name).unwrap();
        node.local.w_axis.truncate()
    };
    // The other unit is of the first one's variant (the same geometry bytes), three rows away:
    // from its close-up the first unit is far enough for its coarse forms.
    let (first, other) = (close_up(0.0), close_up_at(unit("unit 12"), 0.0));
    // How much full detail the close-up of the first unit brings, under a budget that holds it.
    let (_, probe, _) = render(&scene, Some(1 << 20), &[first]);
    let roomy = probe[0].unwrap().total_full_bytes / u64::from(UNITS) * 2;
    let mut session = session(&scene, Some(roomy), Some("gpu-clusters"));
    let coarse = draw(&mut session, &first).0;
    assert!(draw_until_full_detail(&mut session, &first, &coarse));
    let needed = draw(&mut session, &first).1.full_bytes;
    drop(session);

    // A budget of just that: looking at another unit of the same size puts every geometry of
    // the first back in its coarse form.
    let mut session = self::session(&scene, Some(needed), Some("gpu-clusters"));
    let coarse = draw(&mut session, &first).0;
    assert!(draw_until_full_detail(&mut session, &first, &coarse));
    let mut report = None;
    for _ in 0..CONVERGENCE_FRAMES {
        report = Some(draw(&mut session, &other).1);
    }
    let report = report.unwrap();
    // Only the other unit's full detail is held: every geometry of the first went back.
    assert!(
        report.streamed_bytes > needed && report.full_bytes == report.streamed_bytes - needed,
        "the other unit came within the budget: {report:?}"
    );
    // The first unit's coarse forms were kept on the GPU: the same picture as its first frame.
    let back = draw(&mut session, &first).0;
    let difference = compare(&back, &coarse).unwrap();
    println!("back to the first unit: {difference:?} against its first frame; {report:?}");
    assert_eq!(difference.mean, 0.0, "{difference:?}");
    assert!(
        draw_until_full_detail(&mut session, &first, &coarse),
        "and its full detail comes back"
    );
    let Session { device, view, .. } = session;
    drop(view);
    assert_no_validation_errors(&device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
}

#[test]
fn coarse_forms_laid_out_again_draw_as_they_did() {
    let scene = unique_parts();
    let (_, probe, _) = render(&scene, Some(1 << 20), &[close_up(0.0)]);
    let budget = probe[0].unwrap().total_full_bytes / BUDGET_SHARE;
    let mut session = session(&scene, Some(budget), Some("gpu-clusters"));
    // A threshold no coarse form's error reaches: nothing is asked for, all stays coarse.
    session.view.techniques_mut().set_lod_error(1e9).unwrap();
    let camera = close_up(0.0);
    let (before, _) = draw(&mut session, &camera);
    let resident_before = session.view.scene().unwrap().resident_bytes();
    // The last unit's flange, far out of view, given texture coordinates and colours (white):
    // the first geometry with them, so the arenas are laid out again (with an attribute
    // arena), every coarse form placed anew from the full detail (streaming keeps them
    // without their arrays once they are on the GPU).
    let last_flange = (scene.geometries.iter())
        .rposition(|g| g.name.starts_with("fine flange"))
        .unwrap();
    let mut with_attributes = scene.geometries[last_flange].clone();
    with_attributes.attributes = vec![VertexAttributes::default(); with_attributes.vertices.len()];
    let handle = session
        .graph
        .geometry_handle_at(last_flange as u32)
        .unwrap();
    session
        .graph
        .replace_geometry(handle, with_attributes)
        .unwrap();
    session.tree.update(&mut session.graph);
    let (after, report) = draw(&mut session, &camera);
    let resident_after = session.view.scene().unwrap().resident_bytes();
    assert!(
        resident_after > resident_before,
        "the arenas were laid out again: {resident_before} → {resident_after} bytes"
    );
    let difference = compare(&after, &before).unwrap();
    println!("{difference:?}; {report:?}");
    assert_eq!(difference.mean, 0.0, "{difference:?}");
    assert_eq!(report.full_bytes, 0, "{report:?}");
    let Session { device, view, .. } = session;
    drop(view);
    assert_no_validation_errors(&device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
}

/// The coarse forms' device bytes and the first frame's picture of `scene` under `budget`,
/// seen from `camera` (gpu-clusters at 1 px).
fn coarse_forms_under(scene: &Scene, budget: u64, camera: &Camera) -> (u64, image::RgbaImage) {
    let Session {
        device,
        graph,
        mut tree,
        mut view,
    } = session(scene, Some(budget), Some("gpu-clusters"));
    view.render(&graph, &mut tree, camera).unwrap();
    let image = view.renderer().read_rgba8().unwrap();
    let bytes = view.scene().unwrap().coarse_form_bytes();
    drop(view);
    assert_no_validation_errors(&device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
    (bytes, image)
}

#[test]
fn the_coarse_forms_of_a_scene_far_over_its_budget_take_about_half_of_it() {
    let scene = unique_parts();
    let fitted = fitted_view(&scene);
    let (_, probe, _) = render(&scene, Some(1 << 20), &[fitted]);
    let total = probe[0].unwrap().total_full_bytes;
    let (full, _, _) = render(&scene, None, &[fitted]);
    let covered_full = covered_fraction(&full[0]);
    let mut coarse = Vec::new();
    for share in [BUDGET_SHARE, 8 * BUDGET_SHARE] {
        let budget = total / share;
        let (bytes, image) = coarse_forms_under(&scene, budget, &fitted);
        let covered = covered_fraction(&image);
        println!(
            "budget 1/{share} of {total} bytes: coarse forms {bytes} bytes ({:.2} of the budget), \
             {covered} of the picture covered against {covered_full}",
            bytes as f64 / budget as f64
        );
        assert!(bytes > 0, "the scene streams: it has coarse forms");
        assert!(
            (covered - covered_full).abs() < 0.01,
            "no part missing while coarse: {covered} against {covered_full}"
        );
        coarse.push((budget, bytes));
    }
    // Under a sixth, an eighth of each part's triangles would take more than half the budget:
    // the forms are cut coarser, to about half of it (the share is set from the scene's host
    // bytes, so within a margin).
    let (budget, bytes) = coarse[0];
    assert!(
        bytes * 10 <= budget * 6,
        "{bytes} bytes of coarse forms, budget {budget}"
    );
    // Under an eighth of that, coarser still, down to the parts' coarsest cuts or stand-ins.
    assert!(coarse[1].1 * 2 < bytes, "{coarse:?}");
}

/// gen:grid of faceted prisms (every vertex on a crease, which the DAG keeps): 16 geometries
/// of about 250 KB of full detail each.
fn faceted_parts() -> Scene {
    generate(&GeneratorSpec::Grid {
        parts: 1000,
        triangles_per_part: 400.0,
    })
}

#[test]
fn faceted_parts_stream_as_their_stand_ins_and_reach_full_detail_up_close() {
    // The DAG cannot simplify a faceted part past its creases, so its coarse form is one of
    // its stand-ins (before, such geometries had no coarse form and stayed at full detail,
    // over the budget).
    let scene = faceted_parts();
    let fitted = fitted_view(&scene);
    let bounds = flatten(&scene).unwrap().bounds;
    let corner = Aabb {
        min: bounds.min,
        max: bounds.min + (bounds.max - bounds.min) * 0.08,
    };
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let near = Camera::fit(&corner, aspect, DEFAULT_DIRECTION);
    let (full, _, _) = render(&scene, None, &[fitted, near]);
    let (_, probe, _) = render(&scene, Some(1 << 20), &[fitted]);
    let budget = probe[0].unwrap().total_full_bytes / 4;
    let mut session = session(&scene, Some(budget), Some("gpu-clusters"));
    let (coarse, report) = draw(&mut session, &fitted);
    let coarse_bytes = session.view.scene().unwrap().coarse_form_bytes();
    let fitted_difference = compare(&coarse, &full[0]).unwrap();
    let (covered, covered_full) = (covered_fraction(&coarse), covered_fraction(&full[0]));
    println!(
        "budget {budget} of {} bytes: fitted view {fitted_difference:?}, coarse forms \
         {coarse_bytes} bytes, {covered} of the picture covered against {covered_full}",
        report.total_full_bytes
    );
    assert!(report.full_bytes <= budget, "{report:?}");
    assert!(coarse_bytes > 0, "the faceted geometries have coarse forms");
    assert!(fitted_difference.mean <= 0.02, "{fitted_difference:?}");
    assert!((covered - covered_full).abs() < 0.01);
    // Up close the stand-ins' error shows: the few geometries in sight come at full detail.
    let mut converged = None;
    for frame in 0..CONVERGENCE_FRAMES {
        let (image, report) = draw(&mut session, &near);
        assert!(report.full_bytes <= budget, "{report:?}");
        if compare(&image, &full[1]).unwrap().mean <= 1e-4 {
            converged = Some((frame, report));
            break;
        }
    }
    println!("up close: the full-detail picture after {converged:?}");
    let (_, report) = converged.expect("up close, the picture reaches full detail");
    assert!(report.streamed_bytes > 0, "{report:?}");
    drop(session.view);
    assert_no_validation_errors(&session.device);
    std::env::remove_var("CADR_MEMORY_BUDGET");
}

#[test]
fn in_the_edges_mode_the_coarse_forms_draw_the_full_details_edges() {
    // Edges found again on a coarse form's triangles show the creases its simplification
    // makes across smooth faces (FLIP 0.075 against the unbudgeted picture here before); a
    // coarse form draws its part's own edges, at a level within its error (0.014).
    let scene = unique_parts();
    let fitted = fitted_view(&scene);
    let edges_of = |budget: Option<u64>| {
        let mut session = session(&scene, budget, Some("gpu-clusters"));
        let techniques = session.view.techniques_mut();
        techniques.set_shade_mode(ShadeMode::Edges).unwrap();
        let Session {
            device,
            graph,
            mut tree,
            mut view,
        } = session;
        view.render(&graph, &mut tree, &fitted).unwrap();
        let image = view.renderer().read_rgba8().unwrap();
        let report = view.scene().unwrap().streaming();
        drop(view);
        assert_no_validation_errors(&device);
        std::env::remove_var("CADR_MEMORY_BUDGET");
        (image, report)
    };
    let (_, probe) = edges_of(Some(1 << 20));
    let budget = probe.unwrap().total_full_bytes / BUDGET_SHARE;
    let (full, _) = edges_of(None);
    let (coarse, report) = edges_of(Some(budget));
    let report = report.unwrap();
    let difference = compare(&coarse, &full).unwrap();
    println!("edges mode, fitted view, budget {budget}: {difference:?}; {report:?}");
    assert_eq!(report.full_bytes, 0, "the picture is the coarse forms'");
    assert!(difference.mean <= 0.02, "{difference:?}");
}
