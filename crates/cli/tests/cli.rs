//! End-to-end tests of the `vcm` binary: a small render writes its files, and bad input fails
//! with a clear message and a non-zero exit code before any rendering.

use std::path::PathBuf;
use std::process::{Command, Output};

fn vcm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm")).args(args).output().expect("the vcm binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn small_render_writes_linear_image_and_preview() {
    let dir = temp_dir("render");
    let out = dir.join("a.pfm");
    let output =
        vcm(&["render", "--scene", "1", "-a", "pt", "-i", "2", "-r", "32x24", "-o", out.to_str().unwrap(), "--quiet"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let image = io::read_image(&out).unwrap();
    assert_eq!((image.width, image.height), (32, 24));
    assert!(image.channel_means().iter().all(|m| *m > 0.0));
    assert!(dir.join("a.png").exists(), "a PNG preview is written beside a linear output");
    let summary = stderr(&output);
    assert!(summary.contains("2 iterations") && summary.contains("ms/iteration"), "{summary}");
}

#[test]
fn scenes_lists_the_builtins() {
    let output = vcm(&["scenes"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    for name in ["cornell-sun", "cornell-area-mirror", "cornell-point", "cornell-env"] {
        assert!(text.contains(name), "{text}");
    }
}

/// `VCM_ISA` (the queries' instruction-set limit) with a value it does not know is an error
/// that names the accepted values; a known value renders.
#[test]
fn unknown_instruction_set_limit_fails_clearly() {
    let run = |value: &str| {
        Command::new(env!("CARGO_BIN_EXE_vcm")).env("VCM_ISA", value).arg("scenes").output().expect("vcm runs")
    };
    let output = run("sse9");
    assert!(!output.status.success());
    assert!(stderr(&output).contains("VCM_ISA=\"sse9\": expected baseline, avx2 or avx512"), "{}", stderr(&output));
    assert!(run("baseline").status.success());
}

fn assert_fails(args: &[&str], expected: &[&str]) {
    let output = vcm(args);
    assert!(!output.status.success(), "{args:?} should fail");
    let message = stderr(&output);
    for e in expected {
        assert!(message.contains(e), "{args:?}: message {message:?} lacks {e:?}");
    }
}

#[test]
fn bad_input_fails_clearly() {
    let dir = temp_dir("errors");
    let out = dir.join("x.exr");
    let out = out.to_str().unwrap();
    assert_fails(&["render", "--scene", "cornell-moon", "-o", out], &["unknown scene 'cornell-moon'", "cornell-sun"]);
    assert_fails(&["render", "--scene", "7", "-o", out], &["unknown scene '7'"]);
    assert_fails(&["render", "--resolution", "512", "-o", out], &["invalid resolution '512'", "WIDTHxHEIGHT"]);
    assert_fails(&["render", "--resolution", "0x10", "-o", out], &["invalid resolution"]);
    assert_fails(&["render", "--algorithm", "foo", "-o", out], &["invalid value 'foo'", "pt", "vcm"]);
    assert_fails(&["render", "--scene-mask", "1024", "-i", "1", "-o", out], &["invalid scene mask 1024", "0-1023"]);
    assert_fails(
        &["render", "-i", "1", "-o", "/nonexistent-dir/x.exr"],
        &["cannot write output '/nonexistent-dir/x.exr'"],
    );
    assert_fails(
        &["render", "-i", "1", "-o", dir.join("x.bmp").to_str().unwrap()],
        &["unsupported image extension '.bmp'"],
    );
    assert_fails(&["render", "--scene", "missing.xml", "-o", out], &["scene file 'missing.xml' does not exist"]);
    assert_fails(&["render", "--time", "0", "-o", out], &["--time must be a positive number"]);
    assert_fails(&["render", "--mis-compensation", "yes", "-o", out], &["expected 'on' or 'off', got 'yes'"]);
    assert!(!std::path::Path::new(out).exists(), "nothing was written");
}

/// `--mis-compensation` reaches the path tracer and the VCM engine: on a quad lit by an image
/// environment with a bright patch, `off` renders other estimates than the default `on` with
/// the same seed (both estimate the same image; the library's tests compare them), and a
/// constant environment, which has no compensated density, renders the same either way.
#[test]
fn mis_compensation_switch_reaches_every_estimator_it_names() {
    let dir = temp_dir("mis-compensation");
    // A 16 x 8 PFM map (rows bottom first): a bright patch on a dim gradient.
    let (w, h) = (16usize, 8usize);
    let mut pfm = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for y in 0..h {
        for x in 0..w {
            let value: [f32; 3] = if (5..8).contains(&x) && (4..6).contains(&y) {
                [30.0, 24.0, 12.0]
            } else {
                [0.2 + 0.05 * x as f32, 0.5, 0.8]
            };
            for v in value {
                pfm.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(dir.join("sky.pfm"), pfm).unwrap();
    let scene = |emitter: &str| {
        format!(
            r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, -3, 1" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="2"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
    <shape type="sphere"><point name="center" value="0, 0, 0.5"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></shape>
    {emitter}
</scene>
"#
        )
    };
    let image_sky = dir.join("image-sky.xml");
    std::fs::write(&image_sky, scene(r#"<emitter type="envmap"><string name="filename" value="sky.pfm"/></emitter>"#))
        .unwrap();
    let constant_sky = dir.join("constant-sky.xml");
    std::fs::write(&constant_sky, scene(r#"<emitter type="constant"><rgb name="radiance" value="0.7"/></emitter>"#))
        .unwrap();
    let render = |scene: &PathBuf, algorithm: &str, switch: &str| {
        let out = dir.join(format!("{algorithm}-{switch}.pfm"));
        let scene = scene.to_str().unwrap();
        let args = ["render", "--scene", scene, "-a", algorithm, "-i", "2", "--seed", "5", "--quiet"];
        let output = vcm(&[&args[..], &["--mis-compensation", switch, "-o", out.to_str().unwrap()]].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        std::fs::read(&out).unwrap()
    };
    for algorithm in ["pt", "bpt", "vcm"] {
        assert_ne!(render(&image_sky, algorithm, "on"), render(&image_sky, algorithm, "off"), "{algorithm}: image map");
        assert_eq!(
            render(&constant_sky, algorithm, "on"),
            render(&constant_sky, algorithm, "off"),
            "{algorithm}: constant"
        );
    }
}

/// The iteration count recorded in a checkpoint file.
fn checkpoint_iterations(path: &std::path::Path) -> Option<u64> {
    let bytes = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).into_owned();
    text.lines().find_map(|l| l.strip_prefix("iterations=")).and_then(|v| v.parse().ok())
}

#[test]
fn sigint_then_resume_equals_an_uninterrupted_render() {
    let dir = temp_dir("sigint");
    let checkpoint = dir.join("render.ckpt");
    let interrupted = dir.join("interrupted.pfm");
    let common = ["--scene", "1", "-a", "vcm", "-r", "48x40", "--seed", "3", "--quiet"];
    let child = Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(["render", "-i", "1000000", "--checkpoint-every", "0"])
        .args(common)
        .arg("--checkpoint")
        .arg(&checkpoint)
        .arg("-o")
        .arg(&interrupted)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for a few iterations to be checkpointed, then interrupt.
    let start = std::time::Instant::now();
    while checkpoint_iterations(&checkpoint).unwrap_or(0) < 3 {
        assert!(start.elapsed().as_secs() < 60, "no checkpoint written");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "an interrupted render exits cleanly: {message}");
    assert!(message.contains("interrupted"), "{message}");
    let done = checkpoint_iterations(&checkpoint).unwrap();
    let partial = io::read_image(&interrupted).unwrap();
    assert_eq!((partial.width, partial.height), (48, 40), "the image is written on interrupt");

    // Resume to done + 2 iterations, and render the same uninterrupted.
    let total = (done + 2).to_string();
    let resumed = dir.join("resumed.pfm");
    let output = vcm(&[
        "render",
        "--resume",
        checkpoint.to_str().unwrap(),
        "-i",
        &total,
        "--quiet",
        "-o",
        resumed.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let straight = dir.join("straight.pfm");
    let mut args = vec!["render", "-i", &total, "-o", straight.to_str().unwrap()];
    args.extend(common);
    let output = vcm(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    let (a, b) = (io::read_image(&resumed).unwrap(), io::read_image(&straight).unwrap());
    assert!(
        a.pixels.iter().zip(&b.pixels).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits)),
        "resumed image differs"
    );
}

#[test]
fn bad_checkpoints_fail_clearly() {
    let dir = temp_dir("bad-checkpoint");
    let path = dir.join("bad.ckpt");
    std::fs::write(&path, b"not a checkpoint").unwrap();
    let out = dir.join("x.exr");
    assert_fails(
        &["render", "--resume", path.to_str().unwrap(), "-o", out.to_str().unwrap()],
        &["not a valid vcm checkpoint"],
    );
    assert_fails(
        &["render", "--resume", "/nonexistent.ckpt", "-o", out.to_str().unwrap()],
        &["cannot read checkpoint '/nonexistent.ckpt'"],
    );
}

#[test]
fn technique_images_sum_to_the_image() {
    for scene in ["0", "3"] {
        let dir = temp_dir(&format!("techniques-{scene}"));
        let out = dir.join("image.exr");
        let techniques = dir.join("techniques");
        let output = vcm(&[
            "render",
            "--scene",
            scene,
            "-i",
            "3",
            "-r",
            "40x32",
            "--quiet",
            "-o",
            out.to_str().unwrap(),
            "--techniques",
            techniques.to_str().unwrap(),
        ]);
        assert!(output.status.success(), "{}", stderr(&output));
        let image = io::read_image(&out).unwrap();
        let mut sum = vec![[0.0f64; 3]; image.pixels.len()];
        for family in ["emitter-hit", "next-event", "light-tracing", "connection", "merging"] {
            let part = io::read_image(&techniques.join(format!("{family}.exr"))).unwrap();
            for (s, p) in sum.iter_mut().zip(&part.pixels) {
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        for (s, p) in sum.iter().zip(&image.pixels) {
            for c in 0..3 {
                let tolerance = 1e-5 * (p[c].abs() as f64).max(1e-3);
                assert!((s[c] - p[c] as f64).abs() <= tolerance, "scene {scene}: families sum to {} vs {}", s[c], p[c]);
            }
        }
        assert!(techniques.join("vc-vm-share.png").exists() && techniques.join("merging.png").exists());
        // The per-(s, t) images up to the default length 4 (13 connection-type, 6 merges, 5
        // longer buckets) sum to the image too.
        let mut st_images: Vec<String> = std::fs::read_dir(&techniques)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('s') || n.starts_with("merge-") || n.starts_with("longer-"))
            .collect();
        st_images.sort();
        assert_eq!(st_images.len(), 24, "{st_images:?}");
        assert!(st_images.iter().any(|n| n == "s0-t2.exr") && st_images.iter().any(|n| n == "merge-s3-t2.exr"));
        let mut sum = vec![[0.0f64; 3]; image.pixels.len()];
        for name in &st_images {
            let part = io::read_image(&techniques.join(name)).unwrap();
            for (s, p) in sum.iter_mut().zip(&part.pixels) {
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        for (s, p) in sum.iter().zip(&image.pixels) {
            for c in 0..3 {
                let tolerance = 1e-5 * (p[c].abs() as f64).max(1e-3);
                assert!(
                    (s[c] - p[c] as f64).abs() <= tolerance,
                    "scene {scene}: (s, t) images sum to {} vs {}",
                    s[c],
                    p[c]
                );
            }
        }
    }
    let out = temp_dir("techniques-length").join("x.exr");
    for (length, message) in [("0", "technique length must be 1 to 8"), ("9", "technique length must be 1 to 8")] {
        let dir = temp_dir("techniques-length").join("t");
        assert_fails(
            &[
                "render",
                "-i",
                "1",
                "-o",
                out.to_str().unwrap(),
                "--techniques",
                dir.to_str().unwrap(),
                "--technique-length",
                length,
            ],
            &[message],
        );
    }
    assert_fails(&["render", "-i", "1", "-o", out.to_str().unwrap(), "--technique-length", "3"], &["--techniques"]);
    let out = temp_dir("techniques-pt").join("x.exr");
    assert_fails(
        &["render", "-a", "pt", "-i", "1", "-o", out.to_str().unwrap(), "--techniques", "/tmp/t"],
        &["--techniques needs"],
    );
}

#[test]
fn memory_guard_switches_or_stops() {
    let dir = temp_dir("memory");
    let out = dir.join("a.exr");
    let out = out.to_str().unwrap();
    // VCM on 32×32 needs a few hundred KiB; 1K fits neither mode.
    let output =
        vcm(&["render", "--scene", "1", "-a", "vcm", "-i", "1", "-r", "32x32", "--max-memory", "1K", "-o", out]);
    assert_eq!(output.status.code(), Some(2));
    let message = stderr(&output);
    assert!(message.contains("more than --max-memory 1 KiB") && message.contains("memory-efficient"), "{message}");
    // BPT stores nothing in the memory-efficient mode: at 512x512 the default mode needs about
    // 56 MiB at the peak, the memory-efficient one about 18 MiB (the guard's note; neither keeps
    // the film's sums of squares here): it switches and renders.
    let output =
        vcm(&["render", "--scene", "1", "-a", "bpt", "-i", "1", "-r", "512x512", "--max-memory", "37M", "-o", out]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stderr(&output).contains("switching to --memory-efficient"), "{}", stderr(&output));
    // A generous limit changes nothing.
    let output =
        vcm(&["render", "--scene", "1", "-a", "vcm", "-i", "1", "-r", "32x32", "--max-memory", "1G", "-o", out]);
    assert!(output.status.success() && !stderr(&output).contains("switching"), "{}", stderr(&output));
    // Malformed sizes are rejected by the parser.
    let output = vcm(&["render", "--max-memory", "lots", "-o", out]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("invalid memory size 'lots'"), "{}", stderr(&output));
}

/// A scene file that reads two more files: an included material and an OBJ mesh.
fn write_scene_with_parts(dir: &std::path::Path) -> [PathBuf; 3] {
    let main = dir.join("main.xml");
    let materials = dir.join("materials.xml");
    let mesh = dir.join("quad.obj");
    std::fs::write(
        &main,
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
    </sensor>
    <include filename="materials.xml"/>
    <shape type="obj"><string name="filename" value="quad.obj"/><ref id="grey"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"#,
    )
    .unwrap();
    std::fs::write(
        &materials,
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.5"/></bsdf></scene>"#,
    )
    .unwrap();
    std::fs::write(&mesh, "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n").unwrap();
    [main, materials, mesh]
}

#[test]
fn resume_refuses_a_changed_scene_and_names_the_file() {
    let dir = temp_dir("resume-changed");
    let [main, materials, mesh] = write_scene_with_parts(&dir);
    let checkpoint = dir.join("c.ckpt");
    let out = dir.join("a.pfm");
    let (checkpoint_arg, out_arg) = (checkpoint.to_str().unwrap(), out.to_str().unwrap());
    let output = vcm(&[
        "render",
        "--scene",
        main.to_str().unwrap(),
        "-a",
        "pt",
        "-i",
        "2",
        "--quiet",
        "--checkpoint",
        checkpoint_arg,
        "-o",
        out_arg,
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let header = String::from_utf8_lossy(&std::fs::read(&checkpoint).unwrap()).into_owned();
    for file in [&main, &materials, &mesh] {
        assert!(header.contains(&format!(" {}\n", file.display())), "{file:?} not recorded in\n{header}");
    }
    // Unchanged: resumes.
    let resume =
        |iterations: &str| vcm(&["render", "--resume", checkpoint_arg, "-i", iterations, "--quiet", "-o", out_arg]);
    let output = resume("3");
    assert!(output.status.success(), "{}", stderr(&output));
    // Each file edited in turn (a comment: the bytes change) is named; restored, it resumes.
    for (file, expected) in [
        (&main, format!("scene file '{}' changed since the checkpoint", main.display())),
        (&materials, format!("'{}', which the scene reads, changed since the checkpoint", materials.display())),
        (&mesh, format!("'{}', which the scene reads, changed since the checkpoint", mesh.display())),
    ] {
        let original = std::fs::read(file).unwrap();
        let mut edited = original.clone();
        edited.extend_from_slice(if file == &mesh { b"# edited\n" } else { b"<!-- edited -->\n" });
        std::fs::write(file, &edited).unwrap();
        assert_fails(
            &["render", "--resume", checkpoint_arg, "-i", "4", "--quiet", "-o", out_arg],
            &[&format!("cannot resume '{checkpoint_arg}'"), &expected],
        );
        std::fs::write(file, &original).unwrap();
    }
    let output = resume("4");
    assert!(output.status.success(), "{}", stderr(&output));
    // A checkpoint of the previous format (no scene record) is refused with the reason.
    let old = dir.join("old.ckpt");
    std::fs::write(&old, header.replacen("vcm-checkpoint 4", "vcm-checkpoint 2", 1)).unwrap();
    assert_fails(
        &["render", "--resume", old.to_str().unwrap(), "-o", out_arg],
        &["has format 2", "does not record the scene", "reads format 4"],
    );
    // One written by another version of vcm.
    let other = dir.join("other.ckpt");
    let version = header.lines().find_map(|l| l.strip_prefix("vcm_version=")).unwrap().to_string();
    std::fs::write(&other, header.replacen(&format!("vcm_version={version}"), "vcm_version=0.0.1", 1)).unwrap();
    assert_fails(
        &["render", "--resume", other.to_str().unwrap(), "-o", out_arg],
        &["written by vcm 0.0.1 (checkpoint format 4)", &format!("this is vcm {version}")],
    );
}

/// Parses a number column of `vcm bench`, failing with the row.
fn number(row: &[&str], index: usize) -> f64 {
    row[index].parse().unwrap_or_else(|_| panic!("column {index} of {row:?} is not a number"))
}

#[test]
fn bench_prints_every_column_with_sane_values() {
    let output = vcm(&["bench", "-s", "1", "-a", "pt,bpt,vcm", "-i", "1", "-r", "16x16", "--threads", "1"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = String::from_utf8_lossy(&output.stdout).into_owned();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    for column in [
        "scene",
        "algorithm",
        "ms/iteration",
        "CPU-s/iter",
        "light vertices",
        "B/vertex",
        "threads",
        "peak RSS KiB",
        "guard KiB",
    ] {
        assert!(header.contains(column), "{header}");
    }
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split_whitespace().collect()).collect();
    assert_eq!(rows.len(), 3, "{text}");
    for (row, algorithm) in rows.iter().zip(["pt", "bpt", "vcm"]) {
        assert!(row.len() >= 9, "{row:?}");
        assert_eq!((row[0], row[1]), ("cornell-area-mirror", algorithm));
        let ms = number(row, 2);
        assert!(ms > 0.0 && ms < 60e3, "{row:?}");
        assert!(number(row, 3) >= 0.0, "{row:?}");
        assert_eq!(row[6], "1", "threads: {row:?}");
        // A process with the binary mapped and a 16x16 film: more than 1 MiB, far below 1 GiB.
        let peak = number(row, 7);
        assert!(peak > 1024.0 && peak < 1024.0 * 1024.0, "peak RSS: {row:?}");
        if algorithm == "pt" {
            assert_eq!(&row[4..6], ["-", "-"], "{row:?}");
        } else {
            let (vertices, bytes) = (number(row, 4), number(row, 5));
            assert!(vertices > 0.0 && (16.0..=512.0).contains(&bytes), "{row:?}");
        }
        // The guard's estimate (resident memory before the render plus the render's buffers,
        // docs/memory.md) against the measured peak; at 16x16 both are mostly the process.
        let guard = number(row, 8);
        assert!(guard > 0.75 * peak && guard < 1.33 * peak, "guard estimate against peak: {row:?}");
    }
}
