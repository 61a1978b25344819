//! The sample programs, built with the strict flags and run: `headless` writes its PNG,
//! `animate` explodes a scene and reports its costs, and `viewer` runs under Xvfb on lavapipe:
//! it opens, renders, swaps every technique kind, resizes, and a screenshot of its window
//! matches the offscreen render of the same view; `gl_view` shows the frames in an OpenGL
//! window through shared memory (or read back), and its window matches too. The Qt sample
//! `qt_viewer`, built with CMake against the installed package, picks into its model tree,
//! highlights from it, and its view matches the offscreen render too.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

use cadr_tests::c_programs::{build_c_program, describe, repository, scratch_dir};

fn sample(name: &str, dir: &Path, extra: &[&str]) -> PathBuf {
    let program = dir.join(name);
    let mut sources = vec![
        repository().join(format!("samples/{name}.c")),
        repository().join("samples/common/sample.c"),
    ];
    if extra.contains(&"-lGL") {
        // The OpenGL samples bring cadr's frames into their windows through it.
        sources.push(repository().join("samples/common/gl_frames.c"));
    }
    let include = format!("-I{}", repository().join("samples").display());
    let mut flags = vec![include.as_str()];
    flags.extend_from_slice(extra);
    build_c_program(&sources, &program, &flags);
    program
}

/// Pixels that differ from the left edge of their row (the background: a vertical gradient,
/// or one colour).
fn foreground_fraction(image: &image::RgbaImage) -> f64 {
    let differing = image
        .enumerate_pixels()
        .filter(|(_, y, p)| {
            let background = image.get_pixel(0, *y);
            (0..3)
                .map(|c| p[c].abs_diff(background[c]) as u32)
                .sum::<u32>()
                > 30
        })
        .count();
    differing as f64 / f64::from(image.width() * image.height())
}

#[test]
fn headless_builds_an_assembly_and_writes_a_png() {
    let dir = scratch_dir("sample-headless");
    let program = sample("headless", &dir, &[]);
    let png = dir.join("assembly.png");
    let output = Command::new(&program)
        .args([png.to_str().unwrap(), "320", "240"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", describe(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("53 parts shown"), "{}", describe(&output));
    let image = image::open(&png).unwrap().to_rgba8();
    assert_eq!(image.dimensions(), (320, 240));
    let fraction = foreground_fraction(&image);
    assert!(
        fraction > 0.1,
        "only {fraction:.3} of the image shows the assembly"
    );
}

#[test]
fn animate_moves_parts_every_frame_and_reports_costs() {
    let dir = scratch_dir("sample-animate");
    let program = sample("animate", &dir, &[]);
    let png = dir.join("last.png");
    let output = Command::new(&program)
        .args(["gen:demo", "30", png.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", describe(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("pieces explode"), "{}", describe(&output));
    let frame_line = stdout
        .lines()
        .find(|l| l.starts_with("frame 30:"))
        .unwrap_or_else(|| panic!("no report for frame 30\n{}", describe(&output)));
    // The edits upload matrices: something must have been uploaded on a moving frame.
    assert!(
        !frame_line.contains(" 0 bytes uploaded"),
        "a frame with moved parts uploaded nothing: {frame_line}"
    );
    assert!(stdout.contains("mean per frame"), "{}", describe(&output));
    assert!(foreground_fraction(&image::open(&png).unwrap().to_rgba8()) > 0.01);
}

/// An X server for one test; killed when dropped.
struct VirtualDisplay {
    server: Child,
    name: String,
}

impl VirtualDisplay {
    fn start() -> Self {
        for number in (60 + std::process::id() % 200)..(60 + std::process::id() % 200 + 40) {
            // A display is taken while the server its lock names runs; a lock left by a killed
            // server (these tests kill theirs) is stale, and Xvfb takes it over.
            let taken = std::fs::read_to_string(format!("/tmp/.X{number}-lock"))
                .ok()
                .and_then(|pid| pid.trim().parse::<u32>().ok())
                .is_some_and(|pid| Path::new(&format!("/proc/{pid}")).exists());
            if taken {
                continue;
            }
            let mut server = Command::new("Xvfb")
                .args([
                    &format!(":{number}"),
                    "-screen",
                    "0",
                    "1024x768x24",
                    "-nolisten",
                    "tcp",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("run Xvfb (scripts/setup.sh installs xvfb)");
            let socket = format!("/tmp/.X11-unix/X{number}");
            // The display is ours once its lock names our server: another test's server may
            // have taken the number meanwhile (its socket exists, and ours exits).
            let lock = format!("/tmp/.X{number}-lock");
            let ours = |server: &Child| {
                std::fs::read_to_string(&lock)
                    .is_ok_and(|pid| pid.trim().parse::<u32>().ok() == Some(server.id()))
            };
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                if Path::new(&socket).exists() && ours(&server) {
                    return Self {
                        server,
                        name: format!(":{number}"),
                    };
                }
                if let Ok(Some(_)) = server.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = server.kill();
            let _ = server.wait();
        }
        panic!("no Xvfb display could be started");
    }
}

impl Drop for VirtualDisplay {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// The `width` × `height` pixels at `(left, top)` of an XWD screen dump (ZPixmap, 24-bit
/// colour, as Xvfb's `xwd -root` writes them).
fn xwd_region(bytes: &[u8], (left, top): (u32, u32), width: u32, height: u32) -> image::RgbaImage {
    let field = |i: usize| u32::from_be_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
    let (header_size, format, screen_width, screen_height) =
        (field(0), field(2), field(4), field(5));
    let (byte_order, bytes_per_line, colors) = (field(7), field(12), field(19));
    let (red_mask, green_mask, blue_mask) = (field(14), field(15), field(16));
    assert_eq!(format, 2, "XWD is not a ZPixmap");
    assert!(left + width <= screen_width && top + height <= screen_height);
    // Xvfb's depth-24 dumps say 24 bits per pixel (packed) with 32-bit-padded line lengths.
    let bytes_per_pixel = (field(11) / 8) as usize;
    assert!(
        (3..=4).contains(&bytes_per_pixel),
        "expected 24- or 32-bit pixels"
    );
    let pixels = &bytes[(header_size + colors * 12) as usize..];
    let channel = |value: u32, mask: u32| ((value & mask) >> mask.trailing_zeros()) as u8;
    image::RgbaImage::from_fn(width, height, |x, y| {
        let at =
            (top + y) as usize * bytes_per_line as usize + (left + x) as usize * bytes_per_pixel;
        let raw = &pixels[at..at + bytes_per_pixel];
        let value = if byte_order == 0 {
            raw.iter().rev().fold(0, |v, &b| v << 8 | u32::from(b))
        } else {
            raw.iter().fold(0, |v, &b| v << 8 | u32::from(b))
        };
        image::Rgba([
            channel(value, red_mask),
            channel(value, green_mask),
            channel(value, blue_mask),
            255,
        ])
    })
}

/// A window sample in its self-test: started, and read until it says
/// `screenshot ready WxH[ at X,Y]` (its view's size and place on the screen).
struct WindowSample {
    name: &'static str,
    child: Child,
    lines: std::io::Lines<BufReader<ChildStdout>>,
    /// What it printed up to then.
    transcript: String,
    size: (u32, u32),
    origin: (u32, u32),
}

impl WindowSample {
    /// Starts `command` (the sample `name`) with piped standard streams and reads its output
    /// until the screenshot is ready; panics with what it printed when it ends before.
    fn start(name: &'static str, command: &mut Command) -> Self {
        let mut child = command
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let mut transcript = Vec::new();
        let pair = |text: &str, separator| {
            let (a, b) = text.split_once(separator).unwrap();
            (a.parse::<u32>().unwrap(), b.parse::<u32>().unwrap())
        };
        let (size, origin) = loop {
            let Some(Ok(line)) = lines.next() else {
                let status = child.wait().unwrap();
                let mut stderr = String::new();
                std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr)
                    .unwrap();
                panic!(
                    "{name} ended early ({status}):\n{}\n{stderr}",
                    transcript.join("\n")
                );
            };
            transcript.push(line.clone());
            if let Some(rest) = line.strip_prefix("screenshot ready ") {
                break match rest.split_once(" at ") {
                    Some((size, origin)) => (pair(size, 'x'), pair(origin, ',')),
                    None => (pair(rest, 'x'), (0, 0)),
                };
            }
        };
        Self {
            name,
            child,
            lines,
            transcript: transcript.join("\n"),
            size,
            origin,
        }
    }

    /// Fails unless the sample printed each of `expected`.
    fn assert_printed(&self, expected: &[&str]) {
        for line in expected {
            assert!(
                self.transcript.contains(line),
                "no '{line}' in:\n{}",
                self.transcript
            );
        }
    }

    /// Grabs the screen of `display` while the sample keeps its view presented, lets it
    /// finish (it must report no validation error), and compares its view in the grab with
    /// the offscreen render of the same camera it wrote into `dir`/offscreen.png.
    fn grab_finish_and_compare(self, display: &VirtualDisplay, dir: &Path) {
        let (width, height) = self.size;
        let origin = self.origin;
        let name = self.name;
        let dump = self.grab_and_finish(display);
        compare_region(
            name,
            &dump,
            (origin, (width, height)),
            (dir, "offscreen.png"),
            0.05,
        );
    }

    /// Grabs the screen of `display` (an `xwd -root` dump) while the sample keeps its window
    /// shown, then lets it finish; it must report no validation error.
    fn grab_and_finish(mut self, display: &VirtualDisplay) -> Vec<u8> {
        let dump = Command::new("xwd")
            .args(["-root", "-silent", "-display", &display.name])
            .output()
            .expect("run xwd (scripts/setup.sh installs x11-apps)");
        assert!(dump.status.success(), "{}", describe(&dump));
        self.child
            .stdin
            .take()
            .unwrap()
            .write_all(b"done\n")
            .unwrap();
        let rest: Vec<String> = self.lines.map_while(Result::ok).collect();
        let status = self.child.wait().unwrap();
        assert!(
            status.success(),
            "{} failed ({status}):\n{}\n{}",
            self.name,
            self.transcript,
            rest.join("\n")
        );
        assert!(
            rest.iter().any(|l| l == "validation errors: 0"),
            "{}",
            rest.join("\n")
        );
        dump.stdout
    }
}

/// Compares the region `((left, top), (width, height))` of the screen `dump` with the
/// offscreen render `reference` of the same camera that sample `name` wrote into `dir`
/// (saving the region beside it as `window-REFERENCE`); the reference must show something,
/// more than `least` of its pixels.
fn compare_region(
    name: &str,
    dump: &[u8],
    (origin, (width, height)): ((u32, u32), (u32, u32)),
    (dir, reference): (&Path, &str),
    least: f64,
) {
    let window = xwd_region(dump, origin, width, height);
    window
        .save(dir.join(format!("window-{reference}")))
        .unwrap();
    let offscreen = image::open(dir.join(reference)).unwrap().to_rgba8();
    assert_eq!(offscreen.dimensions(), (width, height));
    let shown = foreground_fraction(&offscreen);
    assert!(
        shown > least,
        "{reference} shows too little: {shown:.4} of its pixels"
    );
    let difference = cadr_tests::images::compare(&window, &offscreen).unwrap();
    assert!(
        difference.within(cadr_tests::images::DEFAULT_TOLERANCE),
        "{name}'s window and {reference} differ: {difference:?} (images in {})",
        dir.display()
    );
}

#[test]
fn viewer_under_xvfb_swaps_techniques_resizes_and_shows_the_offscreen_image() {
    let dir = scratch_dir("sample-viewer");
    let program = sample("viewer", &dir, &["-lglfw"]);
    let display = VirtualDisplay::start();
    let viewer = WindowSample::start(
        "viewer",
        Command::new(&program)
            .args(["gen:demo", "--self-test", dir.to_str().unwrap()])
            .env("DISPLAY", &display.name)
            // Frames overlap the window's blits (two in flight): the validation layer's
            // synchronization checks look for a missing barrier, which lavapipe would not
            // show.
            .env(
                "VK_LAYER_ENABLES",
                "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT",
            ),
    );
    viewer.assert_printed(&[
        "rendered 3 frames",
        "vertex technique: ",
        "params technique: ",
        "submit technique: ",
        "cull technique: ",
        "transparency technique: per-pixel-lists",
        "display mode: edges",
        "display mode: hidden-line",
        "display mode: wireframe",
        "display mode: xray",
        "section: x",
        "section caps: off",
        "section hatching: on",
        "background: white",
        "background: dark",
        "background: gradient",
        "anti-aliasing: MSAA ",
        "anti-aliasing: 1 sample (off)",
        "hidden edges: dashed",
        "ambient occlusion: on",
        "silhouettes: off",
        "selected node ",
        "highlight style: outline",
        "highlight style: tint",
        "selection cleared",
        "present modes offered: fifo",
        "resized to 480x360",
    ]);
    assert!(
        !viewer.transcript.contains("no other one fits"),
        "a kind could not be swapped:\n{}",
        viewer.transcript
    );
    // The viewer's window is at 0,0 (no window manager).
    viewer.grab_finish_and_compare(&display, &dir);
}

/// Runs `gl_view` on gen:demo for `frames` frames with `extra` arguments in its self-test,
/// checks that it printed each of `expected`, compares its window with the offscreen render and
/// returns what it printed.
fn run_gl_view(name: &str, frames: &str, extra: &[&str], expected: &[&str]) -> String {
    let dir = scratch_dir(name);
    let program = sample("gl_view", &dir, &["-lglfw", "-lGL"]);
    let display = VirtualDisplay::start();
    let view = WindowSample::start(
        "gl_view",
        Command::new(&program)
            .args(["gen:demo", "--frames", frames])
            .args(extra)
            .args(["--self-test", dir.to_str().unwrap()])
            .env("DISPLAY", &display.name),
    );
    view.assert_printed(expected);
    let transcript = view.transcript.clone();
    view.grab_finish_and_compare(&display, &dir);
    transcript
}

/// The OpenGL host takes cadr's frames through memory the two drivers share (Mesa 25's
/// lavapipe exports it, its llvmpipe imports it): no byte is read back through the CPU, and
/// its window shows what the offscreen render of the same camera shows. Neither driver shares
/// semaphores (lavapipe has no `VK_KHR_external_semaphore_fd`, llvmpipe no
/// `GL_EXT_semaphore_fd`), so cadr waits for each frame's copy, and says so.
#[test]
fn gl_view_shows_cadrs_frames_in_opengl_through_shared_memory() {
    run_gl_view(
        "sample-gl-view",
        "8",
        &[],
        &[
            "path: shared memory",
            "cadr waits for each frame's copy",
            "8 frames",
            "bytes read back per frame: 0",
        ],
    );
}

/// An OpenGL host draws its own geometry into cadr's frames with a depth test against their
/// depth (`CadrRendererSettings::depth_to_host`): a rectangle at the scene's median depth
/// covers exactly the pixels whose depth lies behind it, background included, and none in
/// front; through shared memory nothing is read back, and where memory is not shared the depth
/// is read back beside the colour (`cadr_renderer_read_depth`) to the same effect.
#[test]
fn gl_view_draws_its_own_geometry_into_cadrs_frames_by_their_depth() {
    assert_composites(run_gl_view(
        "sample-gl-view-depth",
        "4",
        &["--depth"],
        &[
            "path: shared memory, with depth",
            "bytes read back per frame: 0",
            "depth compositing: 76800 of 76800 pixels agree, ",
        ],
    ));
    assert_composites(run_gl_view(
        "sample-gl-view-depth-read-back",
        "4",
        &["--depth", "--read-back"],
        &[
            "path: read-back, with depth",
            "bytes read back per frame: 614400",
            "depth compositing: 76800 of 76800 pixels agree, ",
        ],
    ));
}

/// Checks gl_view's depth compositing line in `transcript`: the rectangle covers the farther
/// half of the parts and the background, not the whole picture.
fn assert_composites(transcript: String) {
    let drawn_over: u32 = transcript
        .lines()
        .find_map(|line| line.split(" pixels agree, ").nth(1))
        .and_then(|rest| rest.split(' ').next())
        .and_then(|count| count.parse().ok())
        .unwrap();
    // The background (depth 1) and the farther half of the parts, not the nearer half.
    assert!(
        (76_800 / 2..76_800 - 1_000).contains(&drawn_over),
        "{drawn_over} pixels drawn over:\n{transcript}"
    );
}

/// Four views of one scene (top, front, side, perspective) in one OpenGL window: a click picks
/// in the view under it and highlights in all four, every view shows what the offscreen render
/// of its camera shows, and the frames come through shared memory.
#[test]
fn quad_view_shows_four_views_of_one_scene_and_picks_in_each() {
    let dir = scratch_dir("sample-quad-view");
    let program = sample("quad_view", &dir, &["-lglfw", "-lGL"]);
    let display = VirtualDisplay::start();
    let view = WindowSample::start(
        "quad_view",
        Command::new(&program)
            .args([
                "gen:graphicscard",
                "--frames",
                "4",
                "--self-test",
                dir.to_str().unwrap(),
            ])
            .env("DISPLAY", &display.name),
    );
    view.assert_printed(&[
        "path: shared memory",
        "bytes read back per frame: 0",
        "front view: ",
        "top view: picked node ",
        "side view: picked node ",
        "perspective view: picked node ",
        "device memory: one view ",
        "cadr's host memory: one view ",
    ]);
    let regions: Vec<((u32, u32), (u32, u32))> = (0..4)
        .map(|index| {
            let prefix = format!("view {index} at ");
            let line = view
                .transcript
                .lines()
                .find_map(|l| l.strip_prefix(&prefix))
                .unwrap_or_else(|| panic!("no '{prefix}' in:\n{}", view.transcript));
            let (origin, size) = line.split_once(' ').unwrap();
            let pair = |text: &str, separator| {
                let (a, b) = text.split_once(separator).unwrap();
                (a.parse::<u32>().unwrap(), b.parse::<u32>().unwrap())
            };
            (pair(origin, ','), pair(size, 'x'))
        })
        .collect();
    // The renderers share the scene on the GPU and its mirror on the host: four views hold it
    // once, beside their targets (with a copy each, four views held four times one view's
    // memory). Host memory is cadr's own (`CadrMemoryUsage::host_allocated_bytes`), which the
    // drivers' allocations do not blur as they blur the process's heap.
    for kind in ["device", "cadr's host"] {
        let prefix = format!("{kind} memory: one view ");
        let memory = view
            .transcript
            .lines()
            .find_map(|l| l.strip_prefix(prefix.as_str()))
            .unwrap_or_else(|| panic!("no '{prefix}' in:\n{}", view.transcript));
        let megabytes: Vec<f64> = memory
            .split(' ')
            .filter_map(|word| word.parse().ok())
            .collect();
        let [one, _, four] = megabytes[..] else {
            panic!("{kind} memory line: {memory}");
        };
        assert!(
            one > 0.0 && four < 2.0 * one,
            "{kind}: four views {four} MB, one view {one} MB"
        );
    }
    let dump = view.grab_and_finish(&display);
    for (index, region) in regions.into_iter().enumerate() {
        // A board seen edge-on (front and side) is a thin line.
        compare_region(
            "quad_view",
            &dump,
            region,
            (&dir, &format!("view{index}.png")),
            0.002,
        );
    }
}

/// Where memory cannot be shared (asked for here), the OpenGL host reads frames back and says
/// how many bytes that costs; the picture is the same.
#[test]
fn gl_view_falls_back_to_reading_frames_back() {
    run_gl_view(
        "sample-gl-view-read-back",
        "4",
        &["--read-back"],
        &["path: read-back", "bytes read back per frame: 307200"],
    );
}

#[test]
fn viewer_orbits_with_frames_in_flight_and_reports_frames_per_second() {
    let dir = scratch_dir("sample-viewer-orbit");
    let program = sample("viewer", &dir, &["-lglfw"]);
    let display = VirtualDisplay::start();
    let output = Command::new(&program)
        .args([
            "gen:demo",
            "--orbit-frames",
            "12",
            "--frames-in-flight",
            "3",
        ])
        .env("DISPLAY", &display.name)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", describe(&output));
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(text.contains("| 3 in flight, fifo |"), "{text}");
    let fps: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("orbit: 12 frames, "))
        .and_then(|rest| rest.strip_suffix(" frames/s"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no frames per second in:\n{text}"));
    assert!(fps > 0.0, "{text}");
    let output = Command::new(&program)
        .args(["gen:demo", "--present", "sideways"])
        .env("DISPLAY", &display.name)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("expected fifo, mailbox or immediate"));
}

/// Runs a command to its end, panicking with its output when it fails.
fn run_to_end(command: &mut Command) {
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{command:?}: {}",
        describe(&output)
    );
}

#[test]
fn qt_viewer_picks_into_its_model_tree_highlights_from_it_and_shows_the_offscreen_image() {
    let dir = scratch_dir("sample-qt-viewer");
    let prefix = dir.join("prefix");
    run_to_end(
        Command::new(repository().join("scripts/install.sh"))
            .args(["--prefix", prefix.to_str().unwrap(), "--from"])
            .arg(cadr_tests::c_programs::library_dir()),
    );
    let build = dir.join("build");
    run_to_end(
        Command::new("cmake")
            .arg("-S")
            .arg(prefix.join("share/cadr/samples"))
            .arg("-B")
            .arg(&build)
            .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display())),
    );
    run_to_end(
        Command::new("cmake")
            .arg("--build")
            .arg(&build)
            .args(["--target", "qt_viewer"]),
    );
    let display = VirtualDisplay::start();
    let viewer = WindowSample::start(
        "qt_viewer",
        Command::new(build.join("qt_viewer"))
            .args(["gen:demo", "--self-test", dir.to_str().unwrap()])
            .env("DISPLAY", &display.name)
            .env("QT_QPA_PLATFORM", "xcb")
            .env("XDG_RUNTIME_DIR", &dir)
            .env_remove("CADR_PLUGIN_PATH"),
    );
    viewer.assert_printed(&[
        "rendered ",
        "tree selected ",
        "highlighted in the view: yes",
        "display mode: edges",
        "display mode: hidden-line",
        "display mode: wireframe",
        "display mode: xray",
        "display mode: solid",
        "section: on",
        "section: off",
        "highlighted after clearing: no",
        // The node picked in the middle of the view is a part: a Geo node.
        "(Geo)",
    ]);
    viewer.grab_finish_and_compare(&display, &dir);
}
