//! STUB (replaced by the spectral-data branch).
use crate::Rgb;
pub fn cie_y_integral() -> f32 {
    106.856895
}
pub fn d65_y_integral() -> f32 {
    106.856895
}
pub fn d65(_l: f32) -> f32 {
    1.0
}
pub fn cmf(l: f32) -> [f32; 3] {
    let g = (-((l - 550.0) / 50.0).powi(2)).exp();
    [g, g, g]
}
pub fn xyz_to_linear_srgb(x: [f32; 3]) -> Rgb {
    Rgb::from_array(x)
}
/// stub
pub const CIE_Y_INTEGRAL: f64 = 106.856895;
/// stub
pub const D65_Y_INTEGRAL: f64 = 106.856895;
