//! Turning a [`MediaDesc`] into the scene's [`Media`]: validation and per-primitive interfaces.

use std::ops::Range;

use super::{Media, MediaDesc};
use crate::desc::SceneDescription;

/// The [`Media`] of `desc.media`, whose shape `i` became the world primitives
/// `shape_primitives[i]` (of `primitive_count`). Errors name the medium, shape or material at
/// fault; media together with instanced geometry are refused (issue #15).
pub(crate) fn media(
    media: &MediaDesc,
    shape_primitives: &[Range<usize>],
    primitive_count: usize,
    desc: &SceneDescription,
) -> Result<Media, String> {
    for (index, medium) in media.media.iter().enumerate() {
        medium.validate().map_err(|e| format!("medium {index}: {e}"))?;
    }
    let count = media.media.len();
    let check = |m: Option<u32>, what: &str| match m {
        Some(i) if i as usize >= count => Err(format!("{what} refers to medium {i} of {count}")),
        _ => Ok(()),
    };
    check(media.camera, "the camera")?;
    if let Some(&m) = media.null_materials.iter().find(|&&m| m as usize >= desc.materials.len()) {
        return Err(format!("an index-matched boundary refers to material {m} of {}", desc.materials.len()));
    }
    if !media.shapes.is_empty() && !desc.instances.is_empty() {
        return Err("media together with instanced geometry are not supported yet (issue #15)".to_string());
    }
    let mut interfaces = Vec::new();
    if !media.shapes.is_empty() {
        interfaces = vec![None; primitive_count];
    }
    for (&shape, interface) in &media.shapes {
        let Some(range) = shape_primitives.get(shape as usize) else {
            return Err(format!("a medium interface refers to shape {shape} of {}", shape_primitives.len()));
        };
        let name = &desc.shapes[shape as usize].name;
        check(interface.interior, &format!("shape '{name}' (interior)"))?;
        check(interface.exterior, &format!("shape '{name}' (exterior)"))?;
        for slot in &mut interfaces[range.clone()] {
            *slot = Some(*interface);
        }
    }
    let mut null_materials = Vec::new();
    if !media.null_materials.is_empty() {
        null_materials = vec![false; desc.materials.len()];
        for &m in &media.null_materials {
            null_materials[m as usize] = true;
        }
    }
    Ok(Media { media: media.media.clone(), interfaces, camera: media.camera, null_materials })
}
