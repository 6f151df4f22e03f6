//! pbrt-v4's `nanovdb` medium: `"string filename"` names a NanoVDB file (relative to the scene
//! file) whose float grid `"string gridname"` (default `"density"`) is the density `d`;
//! `σ_a(p) = scale · σ_a · d(p)`, `σ_s(p) = scale · σ_s · d(p)` (`sigma_a`, `sigma_s` rgb or
//! float, default 1; `scale` default 1; `g`). As in pbrt-v4's `NanoVDBMedium`, a medium point
//! (the coordinate system current at `MakeNamedMedium`) is the grid's world space: the grid's
//! own map takes it to index space, where voxel `(i, j, k)` sits at the integer point and
//! lookups are trilinear; the medium fills the grid's stored world bounding box (with a
//! temperature grid, the union with its box) and is empty outside. The grid is decoded into a
//! dense [`Grid`] over the index box that lookups in that region can read (the background
//! value where the file stores nothing), so the lookups are pbrt's.
//!
//! Emission: a float grid `"string temperaturename"` (default `"temperature"`) makes pbrt's
//! medium emit `Lescale · B((T − temperatureoffset) · temperaturescale)` where that exceeds
//! 100 K. Our media do not emit: a temperature grid that would emit somewhere is an error
//! naming the file and line; with `Lescale` 0, or temperatures that stay at most 100 K, it only
//! widens the box, as in pbrt.

use std::path::Path;

use scene::medium::{Coefficient, Coefficients, Grid};

use super::parser::Directive;
use super::transform::Mat4;
use super::{err, resolve};
use crate::nanovdb::{FloatGrid, GridClass, NanoVdbFile};
use crate::scene_error::SceneError;

/// The coefficients of a `nanovdb` medium with the file's `sigma_a` and `sigma_s`, whose
/// medium space is `ctm` of world space.
pub(super) fn nanovdb_grid(
    file: &Path,
    d: &Directive,
    ctm: &Mat4,
    sigma_a: &Coefficient,
    sigma_s: &Coefficient,
) -> Result<Coefficients, SceneError> {
    let p = &d.params;
    super::grid_medium::rgb_coefficients_only(file, d, "nanovdb", sigma_a, sigma_s)?;
    let Some((filename, fpos)) = p.string("filename")? else {
        return Err(err(file, d.pos, "the nanovdb medium needs a \"string filename\""));
    };
    let path = resolve(file, &filename);
    crate::trace::opened(&path);
    let nvdb = NanoVdbFile::read(&path).map_err(|e| p.error(fpos, e))?;
    let at_file = |e: String| p.error(fpos, format!("{}: {e}", path.display()));
    let density_name = p.string("gridname")?.map_or_else(|| "density".to_string(), |(n, _)| n);
    let density = fog_grid(&nvdb, &density_name).map_err(at_file)?.ok_or_else(|| {
        at_file(format!("no grid named \"{density_name}\" (the file holds {})", quoted(&nvdb.names())))
    })?;
    let temperature_name = p.string("temperaturename")?.map_or_else(|| "temperature".to_string(), |(n, _)| n);
    let temperature = fog_grid(&nvdb, &temperature_name).map_err(at_file)?;

    let mut region = density.world_bounds;
    if let Some(t) = &temperature {
        region = [
            std::array::from_fn(|a| region[0][a].min(t.world_bounds[0][a])),
            std::array::from_fn(|a| region[1][a].max(t.world_bounds[1][a])),
        ];
    }
    if !(0..3).all(|a| region[0][a].is_finite() && region[1][a].is_finite() && region[0][a] < region[1][a]) {
        return Err(at_file(format!(
            "grid \"{density_name}\" has an empty world bounding box {:?} – {:?} (no active voxels?)",
            region[0], region[1]
        )));
    }

    let le_scale = p.float("Lescale", 1.0)?;
    let offset = match p.float_opt("temperatureoffset")? {
        Some(o) => o,
        None => p.float("temperaturecutoff", 0.0)?,
    };
    let temperature_scale = p.float("temperaturescale", 1.0)?;
    if let Some(t) = &temperature
        && le_scale != 0.0
    {
        let (lo, dims) = lookup_box(t, &region).map_err(at_file)?;
        let values = t.dense(lo, dims).map_err(at_file)?;
        let hottest = values
            .iter()
            .map(|&v| (v - offset) * temperature_scale)
            .fold(f32::NEG_INFINITY, |m, v| if v.is_nan() { f32::INFINITY } else { m.max(v) });
        if hottest > 100.0 {
            return Err(err(
                file,
                d.pos,
                format!(
                    "nanovdb: the temperature grid \"{temperature_name}\" of {} reaches {hottest} K (after temperatureoffset {offset} and temperaturescale {temperature_scale}), so with Lescale {le_scale} the medium emits; emissive media are not supported (\"float Lescale\" 0 drops the emission)",
                    path.display()
                ),
            ));
        }
    }

    let (lo, dims) = lookup_box(&density, &region).map_err(at_file)?;
    let values = density.dense(lo, dims).map_err(at_file)?;
    let grid = Grid::new(dims, 1, values).map_err(|e| at_file(format!("grid \"{density_name}\": {e}")))?;

    // World → medium → index → the unit cube of the dense grid: u = x − lo, local = (u + ½)/n.
    let world_to_medium = ctm.inverse().ok_or_else(|| err(file, d.pos, "the transformation is singular"))?;
    let index_from_medium = {
        let (m, t) = (density.inverse, density.translation);
        let mt: [f64; 3] = std::array::from_fn(|r| (0..3).map(|c| m[r][c] * t[c]).sum());
        Mat4::from_rows([
            [m[0][0], m[0][1], m[0][2], -mt[0]],
            [m[1][0], m[1][1], m[1][2], -mt[1]],
            [m[2][0], m[2][1], m[2][2], -mt[2]],
            [0.0, 0.0, 0.0, 1.0],
        ])
    };
    let local_from_index = unit_box(
        std::array::from_fn(|a| lo[a] as f64 - 0.5),
        std::array::from_fn(|a| lo[a] as f64 - 0.5 + dims[a] as f64),
    );
    let to_local = super::grid_medium::affine(&local_from_index.mul(&index_from_medium).mul(&world_to_medium))
        .ok_or_else(|| at_file(format!("grid \"{density_name}\": its index-to-world map is singular")))?;
    let region = super::grid_medium::affine(&unit_box(region[0], region[1]).mul(&world_to_medium))
        .ok_or_else(|| err(file, d.pos, "the transformation is singular"))?;
    Ok(super::grid_medium::density_medium(grid, to_local, region, sigma_a.rgb, sigma_s.rgb))
}

/// The float grid `name` of `nvdb`, which must be a fog volume or of unknown class (as pbrt-v4
/// requires), or `None`.
fn fog_grid(nvdb: &NanoVdbFile, name: &str) -> Result<Option<FloatGrid>, String> {
    let Some(grid) = nvdb.float_grid(name)? else { return Ok(None) };
    if grid.class != GridClass::FOG_VOLUME && grid.class != GridClass::UNKNOWN {
        return Err(format!("grid \"{name}\" is a {} grid, expected a fog volume", grid.class.name()));
    }
    Ok(Some(grid))
}

/// The index box a trilinear lookup of `grid` anywhere in the medium-space box `region` reads:
/// its first voxel and size (the floor of the region's index-space bounds to one past the floor
/// of their maximum).
fn lookup_box(grid: &FloatGrid, region: &[[f64; 3]; 2]) -> Result<([i64; 3], [usize; 3]), String> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for corner in 0..8 {
        let w: [f64; 3] = std::array::from_fn(|a| region[(corner >> a) & 1][a] - grid.translation[a]);
        for r in 0..3 {
            let x: f64 = (0..3).map(|c| grid.inverse[r][c] * w[c]).sum();
            lo[r] = lo[r].min(x);
            hi[r] = hi[r].max(x);
        }
    }
    let limit = f64::from(i32::MAX);
    if !(0..3).all(|a| lo[a].is_finite() && hi[a].is_finite() && lo[a].abs() < limit && hi[a].abs() < limit) {
        return Err(format!("grid \"{}\": index-space bounds {lo:?} – {hi:?} are out of range", grid.name));
    }
    let first: [i64; 3] = std::array::from_fn(|a| lo[a].floor() as i64);
    let dims: [usize; 3] = std::array::from_fn(|a| (hi[a].floor() as i64 + 2 - first[a]) as usize);
    let count = dims.iter().try_fold(1u64, |c, &n| c.checked_mul(n as u64)).unwrap_or(u64::MAX);
    if count > crate::nanovdb::MAX_DENSE_VOXELS {
        return Err(format!(
            "grid \"{}\": its dense box of {}×{}×{} voxels is too large (at most {})",
            grid.name,
            dims[0],
            dims[1],
            dims[2],
            crate::nanovdb::MAX_DENSE_VOXELS
        ));
    }
    Ok((first, dims))
}

/// The map of the box `lo`–`hi` onto the unit cube.
fn unit_box(lo: [f64; 3], hi: [f64; 3]) -> Mat4 {
    let s: [f64; 3] = std::array::from_fn(|a| 1.0 / (hi[a] - lo[a]));
    Mat4::from_rows([
        [s[0], 0.0, 0.0, -lo[0] * s[0]],
        [0.0, s[1], 0.0, -lo[1] * s[1]],
        [0.0, 0.0, s[2], -lo[2] * s[2]],
        [0.0, 0.0, 0.0, 1.0],
    ])
}

/// `"a", "b"` for messages.
fn quoted(names: &[&str]) -> String {
    names.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
}
