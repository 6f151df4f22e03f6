//! Prints the merging scale of scene files (`render::vcm::radius::MergingScale`): the scene's
//! bounding-sphere radius R_scene, the visible part's R_vis, s = R_vis / R_scene and the scale
//! the radius factor multiplies, marked `changed` where it is not R_scene.
//!
//! `cargo run --release -p render --example merging_scale -- FILE...` (Mitsuba XML or pbrt-v4
//! files, at their own resolution).

use render::vcm::radius::MergingScale;

fn main() -> Result<(), String> {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        return Err("usage: merging_scale FILE...".into());
    }
    for file in files {
        let built = io::load_scene(std::path::Path::new(&file), &[])
            .map_err(|e| e.to_string())
            .and_then(|desc| scene::Scene::from_description(&desc, None).map_err(|e| e.to_string()));
        let scene = match built {
            Ok((scene, _)) => scene,
            Err(e) => {
                println!("{file}: not loaded: {e}");
                continue;
            }
        };
        let m = MergingScale::of(&scene);
        let visible = m.visible_radius.map_or("-".to_string(), |r| format!("{r:.4}"));
        let s = m.visible_radius.map_or("-".to_string(), |r| format!("{:.3}", r / m.scene_radius));
        let changed = if m.scale == m.scene_radius { "" } else { "  changed" };
        println!("{file}: R_scene {:.4}, R_vis {visible}, s {s}, scale {:.4}{changed}", m.scene_radius, m.scale);
    }
    Ok(())
}
