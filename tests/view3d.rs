//! The 3-D view of `rank`'s report.html in a real headless browser (Chromium, Debian's package
//! `chromium`; TOOLCONF_CHROMIUM names another binary): the page loads with no console message
//! but the software renderer's own performance notes, its script says it is ready, the canvas is
//! drawn (the scene's clear colour, the best tool's blue and the worst tool's red are on screen),
//! and the time slider moves the arm (the canvas at the episode's start, `#t=0`, and end, `#t=1`,
//! differ). Skipped with one line where no Chromium is installed. Everything it writes (the
//! report, the browser's profile and temporary files) is in one folder removed at the end.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CHROMIUM_FLAGS: [&str; 10] = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    // WebGL on the CPU: SwiftShader, which Debian's chromium ships.
    "--use-gl=swiftshader",
    "--enable-unsafe-swiftshader",
];

/// The scene's clear colour (scene.js: 0xf6f7f9).
const CLEAR: [u8; 3] = [0xf6, 0xf7, 0xf9];

fn chromium() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("TOOLCONF_CHROMIUM") {
        return Some(PathBuf::from(path));
    }
    ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .map(PathBuf::from)
        .find(|p| p.is_file())
}

/// What a browser run printed.
struct Output {
    stdout: String,
    stderr: String,
}

/// Chromium on `url` with `args`, its profile, HOME and temporary files under `scratch`, its
/// output into files there (a pipe left unread would stop it: the DOM is 1 MB); killed after two
/// minutes.
fn browse(chromium: &Path, scratch: &Path, args: &[&str], url: &str) -> Output {
    let profile = scratch.join("profile");
    let (stdout, stderr) = (scratch.join("stdout"), scratch.join("stderr"));
    let file = |p: &Path| Stdio::from(std::fs::File::create(p).unwrap());
    let mut child = Command::new(chromium)
        .args(CHROMIUM_FLAGS)
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .arg(url)
        .env("HOME", scratch)
        .env("TMPDIR", scratch)
        .env("XDG_CONFIG_HOME", scratch)
        .env("XDG_CACHE_HOME", scratch)
        .stdout(file(&stdout))
        .stderr(file(&stderr))
        .spawn()
        .expect("chromium starts");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(120) {
            child.kill().unwrap();
            panic!("chromium on {url} did not finish in 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    Output {
        stdout: read(&stdout),
        stderr: read(&stderr),
    }
}

/// `toolconf [before...] rank --tools TOOLS --task TASK --report scratch/r`'s report.html.
fn rank_report(scratch: &Path, before: &[&str], tools: &Path, task: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let report = scratch.join("r");
    let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .current_dir(root)
        .args(before)
        .args(["rank", "--tools"])
        .arg(tools)
        .args(["--task", task, "--report"])
        .arg(&report)
        .output()
        .unwrap();
    common::assert_ok(&out);
    report.join("report.html")
}

/// A screenshot's RGB pixels, row by row.
struct Image {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

fn screenshot(chromium: &Path, scratch: &Path, url: &str, name: &str) -> Image {
    let file = scratch.join(name);
    let shot = format!("--screenshot={}", file.display());
    let out = browse(chromium, scratch, &["--window-size=1000,560", &shot], url);
    assert!(file.is_file(), "no screenshot of {url}: {}", out.stderr);
    let decoder = png::Decoder::new(std::fs::File::open(&file).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buffer).unwrap();
    let channels = info.color_type.samples();
    let rgb = buffer[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Image {
        width: info.width as usize,
        height: info.height as usize,
        rgb,
    }
}

impl Image {
    /// The bounding box (x0, y0, x1, y1) of the pixels of the scene's clear colour: the canvas.
    fn canvas(&self) -> (usize, usize, usize, usize) {
        let mut bounds = (usize::MAX, usize::MAX, 0, 0);
        for (i, p) in self.rgb.iter().enumerate() {
            if p.iter().zip(CLEAR).all(|(a, b)| a.abs_diff(b) <= 2) {
                let (x, y) = (i % self.width, i / self.width);
                bounds = (
                    bounds.0.min(x),
                    bounds.1.min(y),
                    bounds.2.max(x),
                    bounds.3.max(y),
                );
            }
        }
        bounds
    }

    fn count(&self, test: impl Fn(&[u8; 3]) -> bool) -> usize {
        self.rgb.iter().filter(|p| test(p)).count()
    }
}

#[test]
fn the_3d_view_loads_draws_and_moves_in_headless_chromium() {
    let scratch = tempfile::tempdir().unwrap();
    let tools = Path::new("examples/tools/panda_tools.csv");
    let task = "examples/tasks/panda_touch_point.toml";
    check_view(scratch.path(), &[], tools, task);
}

/// The same on the UFactory xArm7, a model loaded from its library: the library in
/// $TOOLCONF_TEST_LIBRARIES/xarm7, which make loaded-models-test builds, and the Panda's
/// catalogue mounted on it (docs/tutorials/add-your-robot.md).
#[test]
#[ignore = "needs the xArm7's model library: make loaded-models-test"]
fn the_3d_view_of_a_loaded_xarm7_in_headless_chromium() {
    let libraries = std::env::var("TOOLCONF_TEST_LIBRARIES").expect("TOOLCONF_TEST_LIBRARIES");
    let library = Path::new(&libraries).join("xarm7");
    let scratch = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let catalogue = std::fs::read_to_string(root.join("examples/tools/panda_tools.csv")).unwrap();
    let tools = scratch.path().join("xarm7_tools.csv");
    std::fs::write(&tools, catalogue.replace(",panda,", ",xarm7,")).unwrap();
    let model_path = format!("--model-path={}", library.display());
    let task = "examples/tasks/xarm7_touch_point.toml";
    check_view(scratch.path(), &[&model_path], &tools, task);
}

fn check_view(scratch: &Path, before: &[&str], tools: &Path, task: &str) {
    let Some(chromium) = chromium() else {
        println!("view3d: skipped: no Chromium (/usr/bin/chromium; Debian's package chromium)");
        return;
    };
    let html = rank_report(scratch, before, tools, task);
    let url = |fragment: &str| format!("file://{}#{fragment}", html.display());

    // Loads, runs, and logs nothing but SwiftShader's performance notes.
    let dom = browse(
        &chromium,
        scratch,
        &["--enable-logging=stderr", "--v=0", "--dump-dom"],
        &url("t=0.5"),
    );
    let page = &dom.stdout;
    assert!(
        page.contains("data-state=\"ready\">3-D view: 101 frames, showing frame 50<"),
        "the view's status is not ready at frame 50: {}",
        page.lines()
            .find(|l| l.contains("view3d-status"))
            .unwrap_or("(no status)")
    );
    let console: Vec<&str> = dom
        .stderr
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .filter(|l| !l.contains("GL Driver Message (OpenGL, Performance"))
        .collect();
    assert!(console.is_empty(), "console messages: {console:#?}");

    // Drawn: the canvas's clear colour fills most of it, both tools' colours are on it.
    let start = screenshot(&chromium, scratch, &url("t=0"), "start.png");
    let end = screenshot(&chromium, scratch, &url("t=1"), "end.png");
    let (x0, y0, x1, y1) = end.canvas();
    assert!(
        x1 > x0 + 600 && y1 > y0 + 300,
        "the canvas's clear colour covers only ({x0}, {y0})–({x1}, {y1}) of {}×{}",
        end.width,
        end.height
    );
    let blue = end.count(|p| p[2] as i32 > p[0] as i32 + 60);
    let red = end.count(|p| p[0] as i32 > p[2] as i32 + 60 && p[0] as i32 > p[1] as i32 + 60);
    assert!(
        blue > 500 && red > 500,
        "the tools are not drawn: {blue} blue, {red} red pixels"
    );

    // The slider moves the arm: inside the canvas, the start and the end differ.
    assert_eq!((start.width, start.height), (end.width, end.height));
    let changed = (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| y * end.width + x))
        .filter(|&i| {
            start.rgb[i]
                .iter()
                .zip(end.rgb[i])
                .any(|(a, b)| a.abs_diff(b) > 40)
        })
        .count();
    assert!(
        changed > 2000,
        "the arm did not move: {changed} pixels of the canvas changed"
    );
}

/// Where there can be no view, the report says why in one line and keeps its 2-D figures: a
/// planar arm (no URDF flange), and a view over its size budget (2,501 output times per episode:
/// some 2 MB of poses against the 1.5 MB budget).
#[test]
fn no_urdf_or_over_budget_gets_one_line_instead_of_the_view() {
    let scratch = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let planar = rank_report(
        scratch.path(),
        &[],
        &root.join("examples/tools/drawer.csv"),
        "examples/tasks/arm2_reach_point.toml",
    );
    let long_task = scratch.path().join("long.toml");
    let touch =
        std::fs::read_to_string(root.join("examples/tasks/panda_touch_point.toml")).unwrap();
    std::fs::write(
        &long_task,
        touch.replace("[episode]", "[episode]\ndt = 0.002"),
    )
    .unwrap();
    let cases = [
        (planar, "There is no 3-D view: model `arm2` has no URDF"),
        (
            rank_report(
                &scratch.path().join("long"),
                &[],
                &root.join("examples/tools/panda_tools.csv"),
                long_task.to_str().unwrap(),
            ),
            "The 3-D view is not written: it would add ",
        ),
    ];
    for (html, line) in cases {
        let md = std::fs::read_to_string(html.with_file_name("report.md")).unwrap();
        let page = std::fs::read_to_string(&html).unwrap();
        assert_eq!(md.matches(line).count(), 1, "{}: {md}", html.display());
        // The HTML has the same line (its `code` marked up) and no view.
        let start = line.split('`').next().unwrap();
        assert_eq!(page.matches(start).count(), 1, "{}", html.display());
        assert!(!page.contains("view3d-canvas"), "{}", html.display());
    }
}
