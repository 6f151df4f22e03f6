//! Eye light: shading by the cosine between the camera ray and the surface normal. A preview
//! of geometry and orientation: front faces are grey `|cos θ|`, back faces red `|cos θ|`.

use math::Ray;
use scene::Scene;
use spectrum::Rgb;

/// The eye-light value for one camera ray.
pub fn eye_light(scene: &Scene, ray: &Ray) -> Rgb {
    match scene.intersect(ray) {
        None => Rgb::BLACK,
        Some(hit) => {
            let cos = hit.normal.dot(-ray.direction);
            if cos > 0.0 { Rgb::splat(cos) } else { Rgb::new(-cos, 0.0, 0.0) }
        }
    }
}
