//! `cohort view` as a person uses it: under a virtual X server (Xvfb), driven by a script
//! of the same keys and drags a person would press, with screenshots of the window taken
//! from the X server, compared with what `cohort render` writes for the same options.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use x11rb::protocol::xproto::{ConnectionExt, ImageFormat};

const SIZE: u32 = 64;
const PATHS: &str = "8";

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
}

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn has_gpu() -> bool {
    cohort::runtime::Device::for_tests(cohort::runtime::BackendKind::Vulkan).is_some()
}

/// An Xvfb server on a free display, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts Xvfb (it picks a free display and writes its number to the pipe). `None` when
/// it is not installed; under CI that is a failure (`.ci/run` installs it).
fn xvfb() -> Option<Xvfb> {
    let started = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1024x768x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn();
    let mut child = match started {
        Ok(c) => c,
        Err(e) => {
            assert!(
                std::env::var("CI").is_err(),
                "Xvfb is needed for the viewer's tests (scripts/install-deps.sh installs it): {e}"
            );
            eprintln!("skipped: no Xvfb ({e}); scripts/install-deps.sh installs it");
            return None;
        }
    };
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let n: u32 = line.trim().parse().expect("Xvfb wrote no display number");
    Some(Xvfb {
        child,
        display: format!(":{n}"),
    })
}

/// RGB bytes of the top-left `SIZE` x `SIZE` pixels of a window, as the X server has them.
fn screenshot(display: &str, window: u64) -> Vec<u8> {
    let (conn, _) = x11rb::connect(Some(display)).unwrap();
    let image = conn
        .get_image(
            ImageFormat::Z_PIXMAP,
            window as u32,
            0,
            0,
            SIZE as u16,
            SIZE as u16,
            !0,
        )
        .unwrap()
        .reply()
        .unwrap();
    assert_eq!(image.depth, 24);
    // 32 bits per pixel, least significant byte first: B, G, R, unused.
    image
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[2], p[1], p[0]])
        .collect()
}

/// An RGB PNG of the test's size: its bytes.
fn read_png(path: &Path) -> Vec<u8> {
    let (w, h, rgb) = read_png_any(path);
    assert_eq!((w, h), (SIZE, SIZE));
    rgb
}

/// Any 8-bit RGB PNG: width, height, bytes.
fn read_png_any(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// `cohort render` of the test's image with extra options; the PNG's RGB bytes.
fn render(dir: &Path, backend: &str, name: &str, extra: &[&str]) -> Vec<u8> {
    let (exr, png) = (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}.png")),
    );
    let out = cohort()
        .args([
            "render",
            "--width",
            "64",
            "--height",
            "64",
            "--paths",
            PATHS,
            "--backend",
            backend,
        ])
        .args(extra)
        .arg("--out")
        .arg(&exr)
        .arg("--png")
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_png(&png)
}

/// Channels of the columns `columns` that differ, and the largest difference. The
/// viewer's `display` kernel and the PNG writer round the same value to 8 bits; a
/// device's `powf` and division may land one step apart.
fn compare(a: &[u8], b: &[u8], columns: std::ops::Range<u32>) -> (usize, u8) {
    let mut differ = 0;
    let mut max = 0;
    for y in 0..SIZE {
        for x in columns.clone() {
            for c in 0..3 {
                let i = ((y * SIZE + x) * 3 + c) as usize;
                let d = a[i].abs_diff(b[i]);
                differ += (d != 0) as usize;
                max = max.max(d);
            }
        }
    }
    (differ, max)
}

fn assert_same(label: &str, shot: &[u8], reference: &[u8], columns: std::ops::Range<u32>) {
    let channels = (columns.len() * SIZE as usize * 3) as f64;
    let (differ, max) = compare(shot, reference, columns);
    assert!(
        max <= 1 && (differ as f64) <= 0.02 * channels,
        "{label}: {differ} of {channels} channels differ from cohort render's PNG, by up to {max}"
    );
}

/// Runs `cohort view` with a script whose `notify` lines each get a screenshot: the
/// script waits for `DIR/shot-K` after its K-th notify. Returns each notify's JSON and
/// screenshot.
fn view(
    x: &Xvfb,
    dir: &Path,
    backend: &str,
    extra: &[&str],
    script: &str,
) -> Vec<(serde_json::Value, Vec<u8>)> {
    let path = dir.join(format!("script-{backend}.txt"));
    std::fs::write(&path, script).unwrap();
    let mut child = cohort()
        .args([
            "view",
            "--width",
            "64",
            "--height",
            "64",
            "--paths",
            PATHS,
            "--backend",
            backend,
        ])
        .args(extra)
        .arg("--script")
        .arg(&path)
        .arg("--out")
        .arg(dir.join("saved.exr"))
        .arg("--png")
        .arg(dir.join("saved.png"))
        .env("DISPLAY", &x.display)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut shots = Vec::new();
    for line in BufReader::new(child.stdout.take().unwrap()).lines() {
        let line = line.unwrap();
        let Ok(json) = serde_json::from_str::<serde_json::Value>(&line) else {
            continue; // `wrote ...` of the save key
        };
        let window = json["window"].as_u64().unwrap();
        assert_ne!(window, 0);
        let shot = screenshot(&x.display, window);
        shots.push((json, shot));
        std::fs::write(dir.join(format!("shot-{}", shots.len())), "").unwrap();
    }
    let status = child.wait().unwrap();
    assert!(status.success(), "cohort view on {backend} failed");
    shots
}

#[test]
fn view_without_a_display_is_a_clear_error() {
    let out = cohort()
        .args(["view", "--width", "16", "--height", "16"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("needs a display") && err.contains("xvfb-run"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn view_script_errors_name_file_and_line() {
    let dir = tempdir("script-error");
    let path = dir.join("bad.txt");
    std::fs::write(&path, "wait-paths 2\njump 3\n").unwrap();
    let out = cohort()
        .arg("view")
        .arg("--script")
        .arg(&path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.txt:2: unknown command `jump`"), "{err}");
    let out = cohort()
        .args(["view", "--compare", "algorithm=warp,colour=red"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--compare: unknown option `colour`"), "{err}");
}

/// The backends the viewer's tests run on, and for each a live change and the render
/// options it amounts to. On the software driver a coherent `extend` takes minutes of LLVM
/// compilation, so the GPU backends switch the interleave factor (same kernels, another
/// pixel order) and the CPU backend, whose kernels are compiled Rust, the algorithm.
fn backends() -> Vec<(&'static str, &'static str, &'static [&'static str])> {
    let mut b: Vec<(&str, &str, &[&str])> = vec![("cpu", "key 3", &["--algorithm", "block_256"])];
    if has_gpu() {
        b.push(("vulkan", "key i", &["--interleave", "3"]));
        b.push(("wgpu", "key i", &["--interleave", "3"]));
    }
    b
}

/// Converges to `cohort render`'s image; a camera move restarts the accumulation (after
/// moving back with the reset key the image is again exactly the render's, which a blend
/// with the moved view would not be); a key switches the configuration live; the save
/// key writes the current estimate.
#[test]
fn view_converges_to_render_restarts_on_camera_moves_and_switches_live() {
    let Some(x) = xvfb() else { return };
    for (backend, key, switched_options) in backends() {
        let dir = tempdir(&format!("single-{backend}"));
        let normal = render(&dir, backend, "normal", &[]);
        let block = render(&dir, backend, "switched", switched_options);
        let d = dir.display();
        let script = format!(
            "wait-paths {PATHS}\nscreenshot {d}/window.png\nnotify converged\nwait-file {d}/shot-1\n\
             drag 40 0\nwait-paths 1\nnotify moved\nwait-file {d}/shot-2\n\
             key r\nwait-paths {PATHS}\nnotify reset\nwait-file {d}/shot-3\n\
             {key}\nwait-paths {PATHS}\nnotify switched\nwait-file {d}/shot-4\n\
             key p\nsleep 200\nquit\n"
        );
        let shots = view(&x, &dir, backend, &[], &script);
        assert_eq!(shots.len(), 4, "{backend}");
        let whole = 0..SIZE;
        let (converged, moved, reset, switched) = (&shots[0], &shots[1], &shots[2], &shots[3]);
        assert_eq!(converged.0["paths_per_pixel"][0].as_f64(), Some(8.0));
        // The panel's figure, for scripts that measure the viewer.
        let rate = converged.0["paths_per_second"][0].as_f64();
        assert!(
            rate.is_some_and(|r| r.is_finite() && r > 0.0),
            "{backend}: {rate:?}"
        );
        assert_same(
            &format!("{backend} converged"),
            &converged.1,
            &normal,
            whole.clone(),
        );
        // The move restarted: a new generation, and a different image.
        assert_eq!(moved.0["generation"].as_u64(), Some(1), "{backend}");
        let (differ, _) = compare(&moved.1, &normal, whole.clone());
        assert!(
            differ > (SIZE * SIZE) as usize,
            "{backend}: the camera move changed {differ} channels only"
        );
        assert_eq!(reset.0["generation"].as_u64(), Some(2));
        assert_same(
            &format!("{backend} reset"),
            &reset.1,
            &normal,
            whole.clone(),
        );
        assert_eq!(switched.0["generation"].as_u64(), Some(3));
        assert_same(
            &format!("{backend} {key}"),
            &switched.1,
            &block,
            whole.clone(),
        );
        // The save key wrote the switched configuration's image.
        assert_same(
            &format!("{backend} saved"),
            &read_png(&dir.join("saved.png")),
            &block,
            whole,
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Side by side: the left half is the first configuration's, the right half the
/// compared one's, each converged to what `cohort render` writes for it.
#[test]
fn view_compares_two_configurations_side_by_side() {
    let Some(x) = xvfb() else { return };
    for (backend, _, _) in backends() {
        let dir = tempdir(&format!("compare-{backend}"));
        // As above: another algorithm on the CPU backend, other options on the GPU ones.
        let (compare, options): (&str, &[&str]) = if backend == "cpu" {
            (
                "algorithm=grid,interleave=5",
                &["--algorithm", "grid", "--interleave", "5"],
            )
        } else {
            (
                "interleave=5,compact=on",
                &["--interleave", "5", "--compact"],
            )
        };
        let normal = render(&dir, backend, "normal", &[]);
        let grid = render(&dir, backend, "compared", options);
        let d = dir.display();
        let script = format!("wait-paths {PATHS}\nnotify both\nwait-file {d}/shot-1\nquit\n");
        let shots = view(&x, &dir, backend, &["--compare", compare], &script);
        assert_eq!(shots.len(), 1);
        let (json, shot) = &shots[0];
        assert_eq!(
            json["paths_per_pixel"],
            serde_json::json!([8.0, 8.0]),
            "{backend}"
        );
        assert_same(&format!("{backend} left"), shot, &normal, 0..SIZE / 2);
        assert_same(&format!("{backend} right"), shot, &grid, SIZE / 2..SIZE);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
