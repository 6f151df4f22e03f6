//! STUB
pub fn sample_visible(u: f32) -> f32 {
    360.0 + 470.0 * u
}
pub fn visible_pdf(_l: f32) -> f32 {
    1.0 / 470.0
}
