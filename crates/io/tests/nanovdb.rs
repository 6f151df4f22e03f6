//! NanoVDB files and pbrt-v4's `nanovdb` medium, against fixtures written by the official
//! NanoVDB library (`scripts/nanovdb-fixture.cpp`, in `tests/data/nanovdb/`):
//!
//! - every voxel of the decoded ramp grid (three boxes, one pruned to tiles, negative indices
//!   across node boundaries; uncompressed and ZIP) equals the formula the generator used;
//! - the medium at 400 world points equals NanoVDB's own world-to-index map and trilinear
//!   sampler (`ramp-samples.txt`), also through a pbrt transformation, and equals the same grid
//!   written as a pbrt `uniformgrid`;
//! - pbrt's clipping to the grid's world box: a grid with a zero outer layer (`rim.nvdb`) is
//!   the same medium as its `uniformgrid` everywhere, and a non-zero outer layer is cut;
//! - the background fills voxels without values;
//! - errors (file, line, what): missing grid, truncated and corrupted files, wrong magic,
//!   Blosc and unknown codecs, a double grid, a level set, emitting temperature grids.

use std::io::Read;
use std::path::{Path, PathBuf};

use io::nanovdb::NanoVdbFile;
use math::rng::Rng;
use scene::desc::SceneDescription;
use scene::medium::Medium;
use spectrum::Rgb;
use testkit::TempDir;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/nanovdb").join(name)
}

/// A fresh directory holding copies of the fixtures, `ramp.nvdb` gunzipped; removed when the
/// guard is dropped.
fn fixtures() -> TempDir {
    let dir = TempDir::new("nanovdb-test");
    for f in ["ramp-zip.nvdb", "fire.nvdb", "background.nvdb", "double.nvdb", "levelset.nvdb"] {
        std::fs::copy(data(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join("ramp.nvdb"), ramp_bytes()).unwrap();
    dir
}

/// The uncompressed ramp file.
fn ramp_bytes() -> Vec<u8> {
    let gz = std::fs::read(data("ramp.nvdb.gz")).unwrap();
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(&gz[..]).read_to_end(&mut out).unwrap();
    out
}

/// The generator's `ramp()`: the density at index (i, j, k).
fn ramp(i: i64, j: i64, k: i64) -> f32 {
    if (-10..=13).contains(&i) && (-3..=6).contains(&j) && (0..=17).contains(&k) {
        return (3 * (i + 10) + 5 * (j + 3) + 7 * k + 1) as f32 / 256.0;
    }
    if (40..=47).contains(&i) && (-3..=-1).contains(&j) && (30..=33).contains(&k) {
        return (32 + (i - 40) + 2 * (j + 3) + 4 * (k - 30)) as f32 / 32.0;
    }
    if (40..=55).contains(&i) && (8..=15).contains(&j) && (0..=7).contains(&k) {
        return 0.75;
    }
    0.0
}

/// Checks the decoded density of `file` against [`ramp`] on its index box grown by 2 voxels.
fn check_ramp(file: &Path) {
    let nvdb = NanoVdbFile::read(file).unwrap();
    let grid = nvdb.float_grid("density").unwrap().expect("a density grid");
    assert_eq!(grid.index_bounds(), [[-10, -3, 0], [55, 15, 33]]);
    assert_eq!(grid.background, 0.0);
    let lo = [-12i64, -5, -2];
    let dims = [70usize, 23, 38];
    let values = grid.dense(lo, dims).unwrap();
    let mut checked = 0;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let (i, j, k) = (lo[0] + x as i64, lo[1] + y as i64, lo[2] + z as i64);
                let v = values[(z * dims[1] + y) * dims[0] + x];
                assert_eq!(v, ramp(i, j, k), "{}: voxel ({i}, {j}, {k})", file.display());
                checked += usize::from(v != 0.0);
            }
        }
    }
    assert_eq!(checked, 24 * 10 * 18 + 8 * 3 * 4 + 16 * 8 * 8);
    // A box that cuts through nodes reads the same values.
    let part = grid.dense([3, -1, 7], [5, 4, 3]).unwrap();
    for (n, v) in part.iter().enumerate() {
        let (x, y, z) = (n % 5, n / 5 % 4, n / 20);
        assert_eq!(*v, ramp(3 + x as i64, -1 + y as i64, 7 + z as i64));
    }
}

#[test]
fn every_voxel_of_the_ramp_matches_its_formula() {
    let dir = fixtures();
    check_ramp(&dir.join("ramp.nvdb"));
    check_ramp(&dir.join("ramp-zip.nvdb"));
    let zip = NanoVdbFile::read(&dir.join("ramp-zip.nvdb")).unwrap();
    assert_eq!(zip.names(), ["other", "density"]);
    let other = zip.float_grid("other").unwrap().unwrap();
    assert_eq!(other.dense([1, 2, 3], [1, 1, 1]).unwrap(), [1.0 + 4.0 + 12.0 + 8.0]);
    assert!(zip.float_grid("velocity").unwrap().is_none());
}

/// The generator's map: `world = 0.05 · Rz(30°) · Rx(20°) · index + (0.3, −0.2, 0.5)`.
#[test]
fn the_index_to_world_map_is_read() {
    let dir = fixtures();
    let grid = NanoVdbFile::read(&dir.join("ramp.nvdb")).unwrap().float_grid("density").unwrap().unwrap();
    let (a, b) = (30f64.to_radians(), 20f64.to_radians());
    let rz = [[a.cos(), -a.sin(), 0.0], [a.sin(), a.cos(), 0.0], [0.0, 0.0, 1.0]];
    let rx = [[1.0, 0.0, 0.0], [0.0, b.cos(), -b.sin()], [0.0, b.sin(), b.cos()]];
    for (r, row) in rz.iter().enumerate() {
        for c in 0..3 {
            let m: f64 = row.iter().zip(&rx).map(|(z, x)| z * x[c]).sum();
            assert!((grid.matrix[r][c] - 0.05 * m).abs() < 1e-12, "{:?}", grid.matrix);
            assert!((grid.inverse[c][r] - m / 0.05).abs() < 1e-9, "{:?}", grid.inverse);
        }
    }
    assert_eq!(grid.translation, [0.3, -0.2, 0.5]);
}

fn pbrt(dir: &Path, body: &str) -> Result<SceneDescription, io::SceneError> {
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, format!("{body}\nWorldBegin\n")).unwrap();
    io::pbrt::load(&path)
}

/// σ_t and σ_s of `medium` at world point `p` (RGB).
fn at(medium: &Medium, p: [f32; 3]) -> (Rgb, Rgb) {
    let h = medium.heterogeneous().expect("a heterogeneous medium");
    h.tracker::<Rgb>(medium.scale, &()).coefficients(math::Vec3::from(p), &())
}

/// Largest density difference accepted between single-precision lookups: the index
/// coordinates of two float computations differ by up to ~10⁻⁵ voxels, and the ramp's density
/// jumps by up to 0.9 between neighbouring voxels at its boxes' faces. (A voxel off, or half a
/// voxel, changes densities by 0.006 or more.)
const TOLERANCE: f32 = 2e-5;

/// `ramp-samples.txt`: world point and NanoVDB's trilinear density there (0 outside the box).
fn samples() -> Vec<([f32; 3], f32)> {
    let text = std::fs::read_to_string(data("ramp-samples.txt")).unwrap();
    text.lines()
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            ([v[0], v[1], v[2]], v[3])
        })
        .collect()
}

#[test]
fn the_medium_samples_as_nanovdb_does() {
    let dir = fixtures();
    for file in ["ramp.nvdb", "ramp-zip.nvdb"] {
        // Identity: medium space is world space. σ_t = 2 · (0.5 + 1) · d, σ_s = 2 · 1 · d.
        let desc = pbrt(
            &dir,
            &format!(
                "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"{file}\" \"float scale\" 2 \"rgb sigma_a\" [0.5 0.5 0.5] \"float sigma_s\" 1"
            ),
        )
        .unwrap();
        let m = &desc.media.media[0];
        let mut inside = 0;
        for (p, d) in samples() {
            let (t, s) = at(m, p);
            assert!((t.g - 3.0 * d).abs() <= 3.0 * TOLERANCE, "{file} at {p:?}: σ_t {t:?}, NanoVDB density {d}");
            assert!((s.b - 2.0 * d).abs() <= 2.0 * TOLERANCE, "{file} at {p:?}: σ_s {s:?}, density {d}");
            inside += usize::from(d > 0.0);
        }
        assert!(inside > 200, "{inside} samples with density");
    }
    // Through a transformation: world = 2 · medium + (1, 2, 3).
    let desc = pbrt(
        &dir,
        "AttributeBegin\nTranslate 1 2 3\nScale 2 2 2\nMakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"ramp.nvdb\" \"float sigma_a\" 1 \"float sigma_s\" 0\nAttributeEnd",
    )
    .unwrap();
    let m = &desc.media.media[0];
    for (q, d) in samples() {
        let p = [2.0 * q[0] + 1.0, 2.0 * q[1] + 2.0, 2.0 * q[2] + 3.0];
        let (t, s) = at(m, p);
        assert!((t.r - d).abs() <= TOLERANCE, "at {p:?}: σ_t {t:?}, density {d}");
        assert_eq!(s.r, 0.0);
    }
}

/// A pbrt `uniformgrid` medium (σ_a 1, σ_s 2) holding `value` of the voxels `lo … lo + n − 1` of
/// `file`'s density grid, voxel `i` at index point `i` (the box from `lo − ½`), placed by the
/// grid's index-to-world map as a pbrt transformation.
fn uniformgrid_of(
    dir: &Path,
    file: &str,
    lo: [i64; 3],
    n: [i64; 3],
    value: impl Fn(i64, i64, i64) -> f32,
) -> SceneDescription {
    let grid = NanoVdbFile::read(&dir.join(file)).unwrap().float_grid("density").unwrap().unwrap();
    let (m, t) = (grid.matrix, grid.translation);
    let mut density = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                density.push(format!("{}", value(lo[0] + i, lo[1] + j, lo[2] + k)));
            }
        }
    }
    let transform = format!(
        "Transform [{} {} {} 0 {} {} {} 0 {} {} {} 0 {} {} {} 1]",
        m[0][0], m[1][0], m[2][0], m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2], t[0], t[1], t[2]
    );
    let p0 = lo.map(|x| x as f64 - 0.5);
    let p1 = [0, 1, 2].map(|a| p0[a] + n[a] as f64);
    pbrt(
        dir,
        &format!(
            "AttributeBegin\n{transform}\nMakeNamedMedium \"u\" \"string type\" \"uniformgrid\" \"integer nx\" {} \"integer ny\" {} \"integer nz\" {} \"point3 p0\" [{} {} {}] \"point3 p1\" [{} {} {}] \"float density\" [{}] \"float sigma_a\" 1 \"float sigma_s\" 2\nAttributeEnd",
            n[0],
            n[1],
            n[2],
            p0[0],
            p0[1],
            p0[2],
            p1[0],
            p1[1],
            p1[2],
            density.join(" ")
        ),
    )
    .unwrap()
}

/// pbrt's `nanovdb` medium of `file`'s density grid, σ_a 1, σ_s 2.
fn nanovdb_of(dir: &Path, file: &str) -> SceneDescription {
    pbrt(
        dir,
        &format!("MakeNamedMedium \"n\" \"string type\" \"nanovdb\" \"string filename\" \"{file}\" \"float sigma_a\" 1 \"float sigma_s\" 2"),
    )
    .unwrap()
}

#[test]
fn nanovdb_equals_the_same_grid_as_a_uniformgrid() {
    // The uniformgrid of the ramp's voxels −12…57 × −5…17 × −2…35 (two zero layers around
    // the active box).
    let dir = fixtures();
    let uniform = uniformgrid_of(&dir, "ramp.nvdb", [-12, -5, -2], [70, 23, 38], ramp);
    let nano = nanovdb_of(&dir, "ramp.nvdb");
    let (u, v) = (&uniform.media.media[0], &nano.media.media[0]);
    for (p, _) in samples() {
        let (a, b) = (at(u, p), at(v, p));
        assert!(
            (a.0.r - b.0.r).abs() <= 3.0 * TOLERANCE && (a.1.r - b.1.r).abs() <= 2.0 * TOLERANCE,
            "{p:?}: {a:?} {b:?}"
        );
    }
}

/// The generator's `rim()`: a ramp strictly inside the box −3…12 × −2…9 × 0…13, 0 on its
/// outer layer and outside.
fn rim(i: i64, j: i64, k: i64) -> f32 {
    let (lo, hi) = ([-3, -2, 0], [12, 9, 13]);
    let c = [i, j, k];
    if (0..3).any(|a| c[a] <= lo[a] || c[a] >= hi[a]) {
        return 0.0;
    }
    (3 * (i - lo[0]) + 5 * (j - lo[1]) + 7 * (k - lo[2])) as f32 / 64.0
}

/// The world point of index-space point `q` under `file`'s map.
fn world(dir: &Path, file: &str, q: [f64; 3]) -> [f32; 3] {
    let grid = NanoVdbFile::read(&dir.join(file)).unwrap().float_grid("density").unwrap().unwrap();
    let (m, t) = (grid.matrix, grid.translation);
    [0, 1, 2].map(|r| (m[r][0] * q[0] + m[r][1] * q[1] + m[r][2] * q[2] + t[r]) as f32)
}

/// pbrt-v4 clips a NanoVDB medium to the grid's world box: the axis-aligned box, in medium
/// space, around the index box of the active voxels from `lo` to `hi + 1` under the grid's map.
/// A `uniformgrid` of the same voxels (voxel `i` at `i`) interpolates from `lo − ½` to `hi + ½`
/// of the index box. With the fixtures' rotated map the two differ only in the parts of the
/// index shell `lo − ½ … lo` outside the world box (along the index box's extreme edges), and
/// only where the outer voxels are not 0. This checks both halves on points around the boxes.
#[test]
fn the_world_box_clips_the_medium_as_in_pbrt() {
    let dir = fixtures();
    std::fs::copy(data("rim.nvdb"), dir.join("rim.nvdb")).unwrap();
    let grid = NanoVdbFile::read(&dir.join("rim.nvdb")).unwrap().float_grid("density").unwrap().unwrap();
    assert_eq!(grid.index_bounds(), [[-3, -2, 0], [12, 9, 13]], "the zero rim is active");
    let uniform = uniformgrid_of(&dir, "rim.nvdb", [-5, -4, -2], [20, 16, 18], rim);
    let nano = nanovdb_of(&dir, "rim.nvdb");
    let (u, v) = (&uniform.media.media[0], &nano.media.media[0]);
    let mut rng = Rng::new(11, 0);
    let mut nonzero = 0;
    for _ in 0..4000 {
        // Index points in the box grown by 1.5 voxels: the shells where the two boxes differ.
        let q = [0, 1, 2].map(|a| {
            let (lo, hi) = ([-3.0, -2.0, 0.0][a], [13.0, 10.0, 14.0][a]);
            lo - 1.5 + (hi - lo + 3.0) * f64::from(rng.uniform())
        });
        let p = world(&dir, "rim.nvdb", q);
        let (a, b) = (at(u, p), at(v, p));
        assert!(
            (a.0.r - b.0.r).abs() <= 3.0 * TOLERANCE && (a.1.r - b.1.r).abs() <= 2.0 * TOLERANCE,
            "index {q:?}: uniformgrid {a:?}, nanovdb {b:?}"
        );
        nonzero += usize::from(b.0.r > 0.0);
    }
    assert!(nonzero > 1000, "{nonzero} points with density");
    // With a non-zero outer layer: the ramp's world z is 0.05 (sin 20° j + cos 20° k) + 0.5,
    // smallest on the index box's edge j = −3, k = 0, where the first box's voxels are non-zero.
    // Beyond that edge the uniformgrid still interpolates; the NanoVDB medium has ended.
    let uniform = uniformgrid_of(&dir, "ramp.nvdb", [-12, -5, -2], [70, 23, 38], ramp);
    let nano = nanovdb_of(&dir, "ramp.nvdb");
    let p = world(&dir, "ramp.nvdb", [0.0, -3.25, -0.25]);
    let (a, b) = (at(&uniform.media.media[0], p), at(&nano.media.media[0], p));
    let expected = 0.75 * 0.75 * ramp(0, -3, 0) * 3.0;
    assert!((a.0.r - expected).abs() <= 3.0 * TOLERANCE, "uniformgrid {a:?}, expected σ_t {expected}");
    assert_eq!(b.0.r, 0.0, "nanovdb outside its world box: {b:?}");
}

#[test]
fn the_background_fills_voxels_without_values() {
    let dir = fixtures();
    let grid = NanoVdbFile::read(&dir.join("background.nvdb")).unwrap().float_grid("density").unwrap().unwrap();
    assert_eq!(grid.background, 0.5);
    assert_eq!(grid.index_bounds(), [[1, 2, 3], [9, 2, 3]]);
    let values = grid.dense([-1, 0, 0], [12, 5, 6]).unwrap();
    for (n, v) in values.iter().enumerate() {
        let p = [n % 12, n / 12 % 5, n / 60].map(|x| x as i64);
        let expected = match [p[0] - 1, p[1], p[2]] {
            [1, 2, 3] => 2.0,
            [9, 2, 3] => 1.0,
            _ => 0.5,
        };
        assert_eq!(*v, expected, "voxel {:?}", [p[0] - 1, p[1], p[2]]);
    }
    // In the medium: the unit map; the box is [1, 10] × [2, 3] × [3, 4]; at index (5, 2.5, 3)
    // the lookup blends voxels (5, 2, 3) and (5, 3, 3), both background.
    let desc = pbrt(&dir, "MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"background.nvdb\" \"float sigma_a\" 1 \"float sigma_s\" 0").unwrap();
    let m = &desc.media.media[0];
    assert!((at(m, [5.0, 2.5, 3.0]).0.r - 0.5).abs() < 1e-6);
    // Halfway between (1, 2, 3) = 2 and (2, 2, 3) = 0.5.
    assert!((at(m, [1.5, 2.0, 3.0]).0.r - 1.25).abs() < 1e-6);
    // Outside the box: empty.
    assert_eq!(at(m, [0.9, 2.5, 3.5]).0.r, 0.0);
}

/// The error of a pbrt scene: at line `line` of the scene file, mentioning every needle.
fn pbrt_error(dir: &Path, body: &str, line: u32, needles: &[&str]) {
    let e = match pbrt(dir, body) {
        Ok(_) => panic!("expected an error for {body}"),
        Err(e) => e,
    };
    let text = e.to_string();
    assert_eq!(e.file, dir.join("scene.pbrt"), "{text}");
    assert_eq!(e.line, Some(line), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{text}' does not mention '{n}'");
    }
}

fn medium(file: &str, extra: &str) -> String {
    format!("MakeNamedMedium \"m\" \"string type\" \"nanovdb\"\n  \"string filename\" \"{file}\" {extra}")
}

#[test]
fn errors_name_the_file_and_what_is_wrong() {
    let dir = fixtures();
    let raw = ramp_bytes();
    let write = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();
    let mut bad = raw.clone();
    bad[0] = b'X';
    write("magic.nvdb", &bad);
    let mut blosc = raw.clone();
    blosc[14] = 2;
    write("blosc.nvdb", &blosc);
    let mut codec = raw.clone();
    codec[14] = 7;
    write("codec.nvdb", &codec);
    write("short.nvdb", &raw[..raw.len() - 100]);
    write("header.nvdb", &raw[..10]);
    let cases: [(&str, &str, &[&str]); 9] = [
        ("nothing.nvdb", "", &["nothing.nvdb", "cannot read"]),
        ("magic.nvdb", "", &["magic.nvdb", "not a NanoVDB file", "NanoVDB0"]),
        ("blosc.nvdb", "", &["blosc.nvdb", "Blosc"]),
        ("codec.nvdb", "", &["codec.nvdb", "unknown codec 7"]),
        ("short.nvdb", "", &["short.nvdb", "truncated"]),
        ("header.nvdb", "", &["header.nvdb", "truncated segment header"]),
        ("double.nvdb", "", &["double.nvdb", "value type double", "only float"]),
        ("levelset.nvdb", "", &["levelset.nvdb", "level set", "fog volume"]),
        (
            "ramp-zip.nvdb",
            "\"string gridname\" \"smoke\"",
            &["ramp-zip.nvdb", "no grid named \"smoke\"", "\"other\", \"density\""],
        ),
    ];
    for (file, extra, needles) in cases {
        pbrt_error(&dir, &medium(file, extra), 2, needles);
    }
    // "gridname" picks another grid.
    pbrt(&dir, &medium("ramp-zip.nvdb", "\"string gridname\" \"other\"")).unwrap();
    pbrt_error(&dir, "MakeNamedMedium \"m\" \"string type\" \"nanovdb\"", 1, &["needs a \"string filename\""]);
    pbrt_error(&dir, &medium("ramp.nvdb", "\"spectrum sigma_a\" [400 1 700 2]"), 1, &["tabulated"]);
}

#[test]
fn emitting_temperature_grids_are_errors() {
    let dir = fixtures();
    // fire.nvdb: a fog sphere and a temperature grid of 1500 K; pbrt's Lescale defaults to 1.
    pbrt_error(&dir, &medium("fire.nvdb", ""), 1, &["fire.nvdb", "temperature", "1500", "emissive", "Lescale"]);
    pbrt_error(&dir, &medium("fire.nvdb", "\"float temperaturescale\" 0.1"), 1, &["150 K"]);
    // No emission: Lescale 0, or temperatures at most 100 K after the offset (also under its
    // older name "temperaturecutoff"), or the scale.
    for extra in [
        "\"float Lescale\" 0",
        "\"float temperatureoffset\" 1400",
        "\"float temperaturecutoff\" 1450",
        "\"float temperaturescale\" 0.05",
    ] {
        let desc = pbrt(&dir, &medium("fire.nvdb", extra)).unwrap_or_else(|e| panic!("{extra}: {e}"));
        let m = &desc.media.media[0];
        // The fog sphere (radius 0.5 at the origin) is 1 at its centre.
        assert!((at(m, [0.0, 0.0, 0.0]).0.r - 2.0).abs() < 1e-5, "{extra}");
        // The temperature grid's box [−0.4, 0.4]³ lies inside the sphere's: the box is the sphere's.
        assert_eq!(at(m, [0.0, 0.0, 0.9]).0.r, 0.0);
    }
}

#[test]
fn corrupted_files_are_errors_not_panics() {
    let dir = fixtures();
    let raw = ramp_bytes();
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15, 0);
    let mut next = move || rng.next_u32();
    let path = dir.join("corrupt.nvdb");
    for round in 0..300 {
        let mut bytes = raw.clone();
        if round % 3 == 0 {
            bytes.truncate(next() as usize % raw.len());
        }
        for _ in 0..(1 + round % 8) {
            let at = next() as usize % bytes.len().max(1);
            if let Some(b) = bytes.get_mut(at) {
                *b = next() as u8;
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(file) = NanoVdbFile::read(&path)
            && let Ok(Some(grid)) = file.float_grid("density")
        {
            let _ = grid.dense([-12, -5, -2], [70, 23, 38]);
        }
    }
    // The dense size guard.
    let grid = NanoVdbFile::read(&dir.join("ramp.nvdb")).unwrap().float_grid("density").unwrap().unwrap();
    let e = grid.dense([0, 0, 0], [1 << 10, 1 << 10, 1 << 10]).unwrap_err();
    assert!(e.contains("too large"), "{e}");
}
