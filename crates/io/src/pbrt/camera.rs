//! The camera, film and filter directives (`Camera`, `Film`, `PixelFilter`) and the camera's description.

use std::path::Path;

use scene::desc::{CameraDesc, FilterDesc, Projection};

use crate::pbrt::parser::Directive;
use crate::pbrt::transform::{dot, norm, normalize};
use crate::scene_error::SceneError;

use super::{Builder, CameraSpec, err, f32v};

impl Builder {
    pub(super) fn camera_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        let orthographic = match ty {
            "perspective" => false,
            "orthographic" => true,
            "realistic" | "spherical" => {
                return Err(err(file, d.arg_pos[0], format!("camera type \"{ty}\" is not supported")));
            }
            _ => return Err(err(file, d.arg_pos[0], format!("unknown camera type \"{ty}\""))),
        };
        let p = &d.params;
        let fov_degrees = if orthographic { 90.0 } else { p.float("fov", 90.0)? };
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            let pos = p.find("fov").map_or(d.pos, |x| x.pos);
            return Err(p.error(pos, format!("fov {fov_degrees} is outside (0, 180) degrees")));
        }
        let lens_radius = p.float("lensradius", 0.0)?;
        let focal_distance = p.float("focaldistance", 1e6)?;
        for name in ["screenwindow", "frameaspectratio"] {
            if let Some(x) = p.find(name) {
                return Err(p.error(x.pos, format!("parameter '{name}' is not supported")));
            }
        }
        let world_from_camera =
            self.state.ctm.inverse().ok_or_else(|| err(file, d.pos, "the camera transformation is singular"))?;
        self.named_coordinate_systems.insert("camera".into(), world_from_camera);
        self.camera = Some(CameraSpec {
            world_from_camera,
            orthographic,
            fov_degrees,
            lens_radius,
            focal_distance,
            file: file.to_path_buf(),
            pos: d.pos,
        });
        self.warn_unused(&d.params);
        Ok(())
    }

    pub(super) fn film_directive(&mut self, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        if !matches!(ty, "rgb" | "gbuffer" | "spectral") {
            return Err(err(
                &d.params.file,
                d.arg_pos[0],
                format!("unknown film type \"{ty}\" (expected rgb or gbuffer)"),
            ));
        }
        let p = &d.params;
        let mut res = [0u32; 2];
        for (k, (name, default)) in [("xresolution", 1280), ("yresolution", 720)].into_iter().enumerate() {
            let v = p.int(name, default)?;
            if !(1..=1 << 16).contains(&v) {
                let pos = p.find(name).map_or(d.pos, |x| x.pos);
                return Err(p.error(pos, format!("{name} {v} is outside 1..=65536")));
            }
            res[k] = v as u32;
        }
        self.resolution = (res[0], res[1]);
        // The output file name is the command line's business.
        let _ = p.find("filename");
        self.warn_unused(p);
        Ok(())
    }

    pub(super) fn filter_directive(&mut self, d: &Directive) -> Result<(), SceneError> {
        let p = &d.params;
        let radius = |default: f32| -> Result<f32, SceneError> {
            let x = p.float("xradius", default)?;
            let y = p.float("yradius", default)?;
            if x != y {
                let pos = p.find("yradius").map_or(d.pos, |q| q.pos);
                return Err(p.error(pos, format!("different xradius ({x}) and yradius ({y}) are not supported")));
            }
            if !(x > 0.0 && x.is_finite()) {
                return Err(p.error(d.pos, format!("filter radius {x} must be positive")));
            }
            Ok(x)
        };
        self.filter = match d.str_arg(0) {
            "box" => {
                let r = radius(0.5)?;
                if r != 0.5 {
                    return Err(p.error(d.pos, format!("box filter radius {r}: only 0.5 is supported")));
                }
                FilterDesc::Box
            }
            "triangle" => FilterDesc::Tent { radius: radius(2.0)? },
            "gaussian" => {
                let stddev = p.float("sigma", 0.5)?;
                if !(stddev > 0.0 && stddev.is_finite()) {
                    return Err(p.error(d.pos, format!("sigma {stddev} must be positive")));
                }
                FilterDesc::Gaussian { stddev, radius: radius(1.5)? }
            }
            ty @ ("mitchell" | "sinc") => {
                return Err(err(&p.file, d.arg_pos[0], format!("pixel filter \"{ty}\" is not supported")));
            }
            ty => return Err(err(&p.file, d.arg_pos[0], format!("unknown pixel filter \"{ty}\""))),
        };
        self.warn_unused(p);
        Ok(())
    }
}

/// The world-space camera for a film of `width × height`.
pub(super) fn camera_desc(spec: &CameraSpec, width: u32, height: u32) -> Result<CameraDesc, SceneError> {
    let w = &spec.world_from_camera;
    let e = |m: &str| err(&spec.file, spec.pos, m.to_string());
    let right = w.vector([1.0, 0.0, 0.0]);
    let up = w.vector([0.0, 1.0, 0.0]);
    let forward = w.vector([0.0, 0.0, 1.0]);
    let (r, u, f) = (
        normalize(right).ok_or_else(|| e("degenerate camera transformation"))?,
        normalize(up).ok_or_else(|| e("degenerate camera transformation"))?,
        normalize(forward).ok_or_else(|| e("degenerate camera transformation"))?,
    );
    if dot(r, u).abs() > 1e-3 || dot(r, f).abs() > 1e-3 || dot(u, f).abs() > 1e-3 {
        return Err(e("the camera transformation shears the camera's axes; not supported"));
    }
    let aspect = f64::from(width) / f64::from(height);
    // pbrt's screen window spans [-1, 1] on the shorter axis.
    let half_width = aspect.max(1.0);
    let projection = if spec.orthographic {
        Projection::Orthographic { width: (2.0 * half_width * norm(right)) as f32 }
    } else {
        let tan_half = (f64::from(spec.fov_degrees).to_radians() * 0.5).tan() * half_width;
        let horizontal_fov_degrees = (2.0 * tan_half.atan()).to_degrees() as f32;
        if spec.lens_radius > 0.0 {
            Projection::ThinLens {
                horizontal_fov_degrees,
                aperture_radius: spec.lens_radius,
                focus_distance: spec.focal_distance,
            }
        } else {
            Projection::Perspective { horizontal_fov_degrees }
        }
    };
    Ok(CameraDesc { position: f32v(w.point([0.0; 3])), forward: f32v(f), up: f32v(u), right: f32v(r), projection })
}
