//! pbrt-v4's `uniformgrid` medium: a density grid `density` of `nx·ny·nz` floats (`x`
//! fastest, each axis default 1) over the medium-space box `p0`–`p1` (default the unit cube),
//! in the coordinate system current at `MakeNamedMedium`. `σ_a(p) = scale · σ_a · d(p)`,
//! `σ_s(p) = scale · σ_s · d(p)`, with pbrt's `SampledGrid` lookup: voxel centres at
//! `(i + ½)/n`, trilinear, zero outside the grid; the medium is empty outside the box. Here
//! σ_t is the grid times `σ_a + σ_s` and σ_s the grid times `σ_s`. `rgbgrid` ([`rgb_grid`])
//! reads RGB grids of σ_a and σ_s. Tabulated spectra and emission (`temperature`, `Le`) are
//! errors naming the file and line.

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec3};
use scene::medium::{Coefficient, Coefficients, Filter, Grid, Heterogeneous, Outside, Volume};
use spectrum::Rgb;

use super::err;
use super::parser::Directive;
use super::transform::Mat4;
use crate::scene_error::SceneError;

/// The coefficients of a `uniformgrid` medium with the file's `sigma_a` and `sigma_s`, whose
/// medium space is `ctm` of world space.
pub(super) fn uniform_grid(
    file: &Path,
    d: &Directive,
    ctm: &Mat4,
    sigma_a: &Coefficient,
    sigma_s: &Coefficient,
) -> Result<Coefficients, SceneError> {
    let p = &d.params;
    rgb_coefficients_only(file, d, "uniformgrid", sigma_a, sigma_s)?;
    if let Some(t) = p.find("temperature") {
        return Err(p.error(t.pos, "uniformgrid: temperature grids (emission) are not supported"));
    }
    let dims = grid_dims(file, d)?;
    let Some((density, pos)) = p.numbers("density", &["float"], 1)? else {
        return Err(err(file, d.pos, "uniformgrid needs a \"float density\" grid"));
    };
    let expected = dims.iter().try_fold(1usize, |c, &n| c.checked_mul(n));
    if expected != Some(density.len()) {
        return Err(p.error(
            pos,
            format!("uniformgrid: {} density values for nx·ny·nz = {}·{}·{}", density.len(), dims[0], dims[1], dims[2]),
        ));
    }
    let grid = Grid::new(dims, 1, density.iter().map(|&v| v as f32).collect()).map_err(|e| p.error(pos, e))?;
    let to_local = grid_to_local(file, d, ctm)?;
    Ok(density_medium(grid, to_local, to_local, sigma_a.rgb, sigma_s.rgb))
}

/// The error of pbrt's density-grid media (`kind`: `uniformgrid`, `nanovdb`) for tabulated
/// `sigma_a` / `sigma_s` spectra: the grid scales RGB (or float) coefficients only.
pub(super) fn rgb_coefficients_only(
    file: &Path,
    d: &Directive,
    kind: &str,
    sigma_a: &Coefficient,
    sigma_s: &Coefficient,
) -> Result<(), SceneError> {
    if sigma_a.spectrum.is_some() || sigma_s.spectrum.is_some() {
        return Err(err(
            file,
            d.pos,
            format!("{kind}: tabulated sigma_a / sigma_s spectra are not supported (rgb or float)"),
        ));
    }
    Ok(())
}

/// The medium of pbrt's density grids (`uniformgrid`, `nanovdb`): σ_t is the one-channel
/// `grid` times `sigma_a + sigma_s`, σ_s the grid times `sigma_s` (per scene unit of length;
/// trilinear, zero outside the grid), through `to_local` (world → the grid's unit cube); the
/// medium fills `region` (world → a unit cube) and is empty outside.
pub(super) fn density_medium(
    grid: Grid,
    to_local: Affine3A,
    region: Affine3A,
    sigma_a: Rgb,
    sigma_s: Rgb,
) -> Coefficients {
    let grid = Arc::new(grid);
    let volume = |value: Rgb| Volume {
        grid: Some(Arc::clone(&grid)),
        value: Coefficient::rgb(value),
        to_local,
        filter: Filter::Trilinear,
        outside: Outside::Zero,
    };
    let albedo = Volume::constant(Coefficient::rgb(Rgb::splat(1.0)), region);
    let (sigma_t, sigma_s) = (volume(sigma_a + sigma_s), volume(sigma_s));
    Coefficients::Heterogeneous(Arc::new(Heterogeneous::new(sigma_t, albedo, Some(sigma_s), region)))
}

/// `nx ny nz` (each default 1, at least 1).
fn grid_dims(file: &Path, d: &Directive) -> Result<[usize; 3], SceneError> {
    let p = &d.params;
    let mut dims = [1usize; 3];
    for (axis, name) in ["nx", "ny", "nz"].iter().enumerate() {
        let n = p.int(name, 1)?;
        dims[axis] = usize::try_from(n)
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| err(file, d.pos, format!("'{name}' is {n}, expected at least 1")))?;
    }
    Ok(dims)
}

/// World → the unit cube of the box `p0`–`p1` of medium space (`ctm` maps medium space to world).
fn grid_to_local(file: &Path, d: &Directive, ctm: &Mat4) -> Result<Affine3A, SceneError> {
    let p = &d.params;
    let point = |name: &str, default: [f64; 3]| -> Result<Vec3, SceneError> {
        match p.numbers(name, &["point3", "point"], 3)? {
            Some((v, _)) if v.len() == 3 => Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)),
            Some((_, pos)) => Err(p.error(pos, format!("'{name}' needs one point"))),
            None => Ok(Vec3::new(default[0] as f32, default[1] as f32, default[2] as f32)),
        }
    };
    let (p0, p1) = (point("p0", [0.0; 3])?, point("p1", [1.0; 3])?);
    let extent = p1 - p0;
    if !(extent.is_finite() && extent.min_element() > 0.0) {
        return Err(err(file, d.pos, format!("the box p0 {p0} – p1 {p1} is empty")));
    }
    let medium_to_world = affine(ctm).ok_or_else(|| err(file, d.pos, "the transformation is singular"))?;
    let to_local = Affine3A::from_scale(extent.recip()) * Affine3A::from_translation(-p0) * medium_to_world.inverse();
    Ok(to_local)
}

/// pbrt-v4's `rgbgrid`: `sigma_a` and `sigma_s` grids of `nx·ny·nz` RGB values each (an absent
/// grid is 1 everywhere, as in pbrt-v4), `scale`, `p0`/`p1`; `σ_a(p) = scale · sigma_a(p)`,
/// `σ_s(p) = scale · sigma_s(p)` with the lookup of `uniformgrid`. σ_t is stored as the grid of
/// `σ_a + σ_s` voxel by voxel, which interpolates to exactly `σ_a(p) + σ_s(p)`.
pub(super) fn rgb_grid(file: &Path, d: &Directive, ctm: &Mat4) -> Result<Coefficients, SceneError> {
    let p = &d.params;
    let dims = grid_dims(file, d)?;
    let count = dims.iter().try_fold(1usize, |c, &n| c.checked_mul(n)).unwrap_or(usize::MAX);
    let grid = |name: &str| -> Result<Option<Vec<f32>>, SceneError> {
        let Some((v, pos)) = p.numbers(name, &["rgb"], 3)? else { return Ok(None) };
        if v.len() / 3 != count {
            return Err(p.error(
                pos,
                format!(
                    "rgbgrid: {} rgb values in '{name}' for nx·ny·nz = {}·{}·{}",
                    v.len() / 3,
                    dims[0],
                    dims[1],
                    dims[2]
                ),
            ));
        }
        if let Some(x) = v.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            return Err(p.error(pos, format!("rgbgrid: '{name}' holds {x}; values must be finite and non-negative")));
        }
        Ok(Some(v.iter().map(|&x| x as f32).collect()))
    };
    let (a, s) = (grid("sigma_a")?, grid("sigma_s")?);
    let ones = vec![1.0f32; count.saturating_mul(3)];
    let (a, s) = (a.unwrap_or_else(|| ones.clone()), s.unwrap_or(ones));
    let t: Vec<f32> = a.iter().zip(&s).map(|(a, s)| a + s).collect();
    let to_local = grid_to_local(file, d, ctm)?;
    let volume = |values: Vec<f32>| -> Result<Volume, SceneError> {
        let grid = Grid::new(dims, 3, values).map_err(|e| err(file, d.pos, e))?;
        Ok(Volume {
            grid: Some(Arc::new(grid)),
            value: Coefficient::rgb(Rgb::splat(1.0)),
            to_local,
            filter: Filter::Trilinear,
            outside: Outside::Zero,
        })
    };
    let albedo = Volume::constant(Coefficient::rgb(Rgb::splat(1.0)), to_local);
    Ok(Coefficients::Heterogeneous(Arc::new(Heterogeneous::new(volume(t)?, albedo, Some(volume(s)?), to_local))))
}

/// The affine part of `m` in single precision; `None` when it is singular, projective or not
/// finite.
pub(super) fn affine(m: &Mat4) -> Option<Affine3A> {
    let column = |c: usize| Vec3::new(m.m[0][c] as f32, m.m[1][c] as f32, m.m[2][c] as f32);
    let affine = Affine3A::from_cols(column(0).into(), column(1).into(), column(2).into(), column(3).into());
    let determinant = affine.matrix3.determinant();
    (m.is_affine() && affine.is_finite() && determinant.is_finite() && determinant != 0.0).then_some(affine)
}
