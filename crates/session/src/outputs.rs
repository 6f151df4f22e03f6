//! The files a render writes: the image and its preview, the variance, the technique images.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use render::vcm::Family;
use render::vcm::technique_images::TechniqueImages;

/// The files a render writes: the requested one and, for linear formats, a PNG preview.
pub fn output_paths(output: &Path) -> Result<Vec<(PathBuf, io::ImageFormat)>> {
    let format = io::ImageFormat::from_path(output)?;
    let mut paths = vec![(output.to_path_buf(), format)];
    if format != io::ImageFormat::Png {
        paths.push((output.with_extension("png"), io::ImageFormat::Png));
    }
    Ok(paths)
}

/// Fails early, before any rendering, if an output cannot be created.
pub fn check_writable(path: &Path) -> Result<()> {
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("cannot write output '{}'", path.display()))?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Writes the per-family images and the false-colour VC/VM share image into `dir`.
pub fn write_technique_images(dir: &Path, families: &[scene::Film; 5], options: &io::WriteOptions) -> Result<()> {
    let means: Vec<Vec<[f32; 3]>> = families.iter().map(|f| f.mean()).collect();
    let (width, height) = (families[0].width() as usize, families[0].height() as usize);
    for (family, pixels) in Family::ALL.iter().zip(&means) {
        let image = io::Image { width, height, pixels: pixels.clone() };
        io::write_image(&dir.join(format!("{}.exr", family.name())), &image, options)?;
        // A preview to browse, exposed like the render's.
        io::write_image(&dir.join(format!("{}.png", family.name())), &image, options)?;
    }
    // Share of vertex merging against all connection techniques, by luminance.
    let luminance = |p: [f32; 3]| spectrum::Rgb::from_array(p).luminance().max(0.0);
    let share = (0..width * height)
        .map(|i| {
            let merging = luminance(means[Family::Merging as usize][i]);
            let total: f32 = means.iter().map(|m| luminance(m[i])).sum();
            if total > 0.0 { [1.0 - merging / total, merging / total, 0.0] } else { [0.0; 3] }
        })
        .collect();
    let image = io::Image { width, height, pixels: share };
    io::write_image(&dir.join("vc-vm-share.png"), &image, &io::WriteOptions::default())?;
    Ok(())
}

/// Writes one image per (s, t) technique into `dir`, named as
/// [`render::vcm::technique_images::TechniqueImage::name`] says.
pub fn write_st_images(
    dir: &Path,
    images: &TechniqueImages,
    width: usize,
    height: usize,
    options: &io::WriteOptions,
) -> Result<()> {
    for (index, technique) in images.layout().images().iter().enumerate() {
        let image = io::Image { width, height, pixels: images.mean(index) };
        io::write_image(&dir.join(format!("{}.exr", technique.name())), &image, options)?;
    }
    Ok(())
}
