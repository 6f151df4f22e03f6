//! Spectra to linear sRGB: pbrt-v4's emission normalisation, blackbodies, piecewise-linear
//! spectra and the named metal and glass spectra.
//!
//! **Emission.** pbrt-v4 divides every light's `scale` by the luminance of its spectrum
//! (`SpectrumToPhotometric`; for an `rgb` value only the colour space's illuminant, D65, counts),
//! so a light with `scale` 1 has luminance 1 whatever its spectrum. We convert a spectrum to
//! CIE XYZ, normalise it to `Y = 1` and convert to linear sRGB (D65 white, no white balancing,
//! as pbrt's default `cie1931` sensor). An `rgb` value is used as given (its illuminant, D65,
//! is sRGB's white). `"spectrum" "stdillum-D65"` is exactly `(1, 1, 1)`.
//!
//! **CIE 1931 observer.** We use the multi-lobe Gaussian fit of Wyman, Sloan and Shirley,
//! "Simple Analytic Approximations to the CIE XYZ Color Matching Functions" (JCGT 2(2), 2013),
//! integrated with a 1 nm midpoint rule over 360–830 nm; its chromaticities agree with the
//! tabulated observer to about 10⁻³.
//!
//! **Metals.** pbrt-v4's named conductor spectra (`metal-Cu-eta`, …; in pbrt they are the
//! tables of `src/pbrt/util/spectrum.cpp`) are reduced to three samples, linearly interpolated
//! in those tables at the dominant wavelengths of the sRGB primaries (611.3, 549.1, 464.3 nm).
//! This is an approximation: a Fresnel curve of RGB samples is not the RGB of the spectral
//! Fresnel curve.
//!
//! **Glasses.** pbrt's named glass spectra (`glass-BK7`, …) become a single index of refraction:
//! the Schott catalogue value n_d at 587.6 nm (dispersion is dropped).

use spectrum::Rgb;

/// Dominant wavelengths (nm) of the sRGB red, green and blue primaries.
pub const PRIMARY_WAVELENGTHS: [f64; 3] = [611.3, 549.1, 464.3];

/// Piecewise Gaussian `exp(−½((λ−μ)/σ)²)` with σ = `s1` below μ and `s2` above.
fn lobe(lambda: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let t = (lambda - mu) / if lambda < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// The CIE 1931 2° colour matching functions x̄, ȳ, z̄ at `lambda` nm (Wyman et al. 2013 fit).
pub fn cie_xyz(lambda: f64) -> [f64; 3] {
    let x = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
        - 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
    [x, y, z]
}

/// ∫ s(λ) (x̄, ȳ, z̄)(λ) dλ over 360–830 nm (1 nm midpoint rule).
pub fn spectrum_to_xyz(s: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for i in 0..470 {
        let lambda = 360.5 + i as f64;
        let v = s(lambda);
        let cmf = cie_xyz(lambda);
        for k in 0..3 {
            xyz[k] += v * cmf[k];
        }
    }
    xyz
}

/// CIE XYZ to linear sRGB (D65 white; IEC 61966-2-1 matrix).
pub fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = xyz;
    [
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    ]
}

/// Planck's law: spectral radiance of a blackbody at `kelvin` and `lambda` nm, up to a constant
/// factor (the factor drops out of the luminance normalisation).
pub fn planck(lambda: f64, kelvin: f64) -> f64 {
    // c2 = h c / k_B in nm·K.
    const C2: f64 = 1.438_776_877e7;
    let l = lambda * 1e-3; // micrometres, to keep the numbers moderate
    1.0 / (l.powi(5) * ((C2 / (lambda * kelvin)).exp() - 1.0))
}

/// The linear sRGB colour of an emission spectrum normalised to luminance `Y = 1` (pbrt-v4's
/// photometric normalisation of lights); `None` when the spectrum has no luminance.
pub fn emission_rgb(s: impl Fn(f64) -> f64) -> Option<Rgb> {
    let xyz = spectrum_to_xyz(s);
    if xyz[1] <= 0.0 || !xyz[1].is_finite() {
        return None;
    }
    let rgb = xyz_to_srgb(xyz.map(|c| c / xyz[1]));
    Some(Rgb::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32))
}

/// The chromaticity (x, y) of a blackbody at `kelvin` (for tests and messages).
pub fn blackbody_chromaticity(kelvin: f64) -> (f64, f64) {
    let [x, y, z] = spectrum_to_xyz(|l| planck(l, kelvin));
    (x / (x + y + z), y / (x + y + z))
}

/// Linear interpolation in a table of `(wavelength, value)` pairs sorted by wavelength.
fn interpolate(table: &[(f64, f64)], lambda: f64) -> f64 {
    let (first, last) = (table[0], table[table.len() - 1]);
    if lambda <= first.0 {
        return first.1;
    }
    if lambda >= last.0 {
        return last.1;
    }
    let i = table.iter().position(|&(l, _)| l > lambda).unwrap_or(table.len() - 1).max(1);
    let ((l0, v0), (l1, v1)) = (table[i - 1], table[i]);
    v0 + (v1 - v0) * (lambda - l0) / (l1 - l0)
}

/// A piecewise-linear spectrum given as `λ₀ v₀ λ₁ v₁ …` (pbrt's inline `"spectrum"` values),
/// zero outside its range as in pbrt. `None` if the wavelengths are not increasing.
pub fn piecewise_linear(pairs: &[f64]) -> Option<impl Fn(f64) -> f64> {
    if pairs.len() % 2 != 0 {
        return None;
    }
    let table: Vec<(f64, f64)> = pairs.chunks_exact(2).map(|c| (c[0], c[1])).collect();
    if table.len() < 2 || table.windows(2).any(|w| w[1].0 <= w[0].0) {
        return None;
    }
    Some(
        move |lambda: f64| {
            if lambda < table[0].0 || lambda > table[table.len() - 1].0 { 0.0 } else { interpolate(&table, lambda) }
        },
    )
}

/// The samples of pbrt-v4's metal tables that bracket the three primary wavelengths: per metal,
/// `(λ, η, k)` at 459.200653, 467.864838, 539.061646, 551.040771, 604.800842 and 619.920898 nm.
/// A metal's name and its `(λ, η, k)` samples.
type MetalSamples = (&'static str, [(f64, f64, f64); 6]);

const METAL_SAMPLES: [MetalSamples; 4] = [
    (
        "Cu",
        [
            (459.200653, 1.160000, 2.433000),
            (467.864838, 1.155312, 2.469187),
            (539.061646, 1.040000, 2.583000),
            (551.040771, 0.950375, 2.576500),
            (604.800842, 0.351250, 3.010750),
            (619.920898, 0.272000, 3.240000),
        ],
    ),
    (
        "Au",
        [
            (459.200653, 1.426000, 1.846000),
            (467.864838, 1.345875, 1.814625),
            (539.061646, 0.402000, 2.540000),
            (551.040771, 0.345500, 2.730625),
            (604.800842, 0.212375, 3.015000),
            (619.920898, 0.194000, 3.060000),
        ],
    ),
    (
        "Ag",
        [
            (459.200653, 0.144000, 2.560000),
            (467.864838, 0.137313, 2.640000),
            (539.061646, 0.129000, 3.250000),
            (551.040771, 0.124375, 3.348125),
            (604.800842, 0.125500, 3.766250),
            (619.920898, 0.131000, 3.880000),
        ],
    ),
    (
        "Al",
        [
            (459.200653, 0.644000, 5.580000),
            (467.864838, 0.668625, 5.690000),
            (539.061646, 0.912000, 6.550000),
            (551.040771, 0.963000, 6.700000),
            (604.800842, 1.220000, 7.310000),
            (619.920898, 1.300000, 7.480000),
        ],
    ),
];

/// The RGB value of a named pbrt-v4 metal spectrum `metal-<M>-eta` / `metal-<M>-k` for
/// M ∈ {Cu, Au, Ag, Al}; `None` for other names.
pub fn named_metal(name: &str) -> Option<Rgb> {
    let rest = name.strip_prefix("metal-")?;
    let (metal, part) = rest.rsplit_once('-')?;
    let column = match part {
        "eta" => 0,
        "k" => 1,
        _ => return None,
    };
    let (_, samples) = METAL_SAMPLES.iter().find(|(m, _)| *m == metal)?;
    let table: Vec<(f64, f64)> = samples.iter().map(|&(l, eta, k)| (l, if column == 0 { eta } else { k })).collect();
    let [r, g, b] = PRIMARY_WAVELENGTHS.map(|l| interpolate(&table, l) as f32);
    Some(Rgb::new(r, g, b))
}

/// The index of refraction n_d (587.6 nm) of pbrt-v4's named glass spectra, from the Schott
/// catalogue (SF5, SF10, SF11 for pbrt's `glass-F5`, `glass-F10`, `glass-F11`).
pub fn named_glass(name: &str) -> Option<f32> {
    Some(match name {
        "glass-BK7" => 1.5168,
        "glass-BAF10" => 1.67003,
        "glass-FK51A" => 1.48656,
        "glass-LASF9" => 1.85025,
        "glass-F5" | "glass-SF5" => 1.67271,
        "glass-F10" | "glass-SF10" => 1.72825,
        "glass-F11" | "glass-SF11" => 1.78472,
        _ => return None,
    })
}
