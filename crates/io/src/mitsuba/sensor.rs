//! `<sensor>` (with its `<film>` and `<rfilter>`) and `<integrator>`.

use math::Vec3;
use scene::desc::{CameraDesc, FilmDesc, FilterDesc, Projection};

use super::Loader;
use super::props::Plugin;
use super::transform::{Mat4, cross, dot, length, normalize, positive, to_vec3};
use super::xml::Node;
use crate::scene_error::SceneError;

/// Mitsuba 3's default `rr_depth` (bounces before its Russian roulette starts).
pub(crate) const MITSUBA_RR_DEPTH: u32 = 5;

/// Mitsuba's film size when none is given.
const DEFAULT_FILM: (u32, u32) = (768, 576);

/// Mitsuba's default sensor: a perspective camera at the origin looking along +z with a 45°
/// horizontal field of view, on the default film.
pub(crate) fn default_sensor() -> (CameraDesc, FilmDesc) {
    (
        CameraDesc {
            position: Vec3::ZERO,
            forward: Vec3::Z,
            up: Vec3::Y,
            right: Vec3::NEG_X,
            projection: Projection::Perspective { horizontal_fov_degrees: 45.0 },
        },
        FilmDesc { width: DEFAULT_FILM.0, height: DEFAULT_FILM.1, filter: default_filter() },
    )
}

/// Mitsuba's default reconstruction filter: a Gaussian of standard deviation 0.5 pixel,
/// truncated at 4σ.
fn default_filter() -> FilterDesc {
    FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }
}

/// Converts a field of view measured along `axis` to the horizontal one, for a film of
/// `width × height` pixels (square pixels).
pub(crate) fn horizontal_fov(fov_degrees: f64, axis: &str, width: u32, height: u32) -> Option<f64> {
    let (w, h) = (f64::from(width), f64::from(height));
    let aspect = w / h;
    let axis = match axis {
        "smaller" => {
            if aspect > 1.0 {
                "y"
            } else {
                "x"
            }
        }
        "larger" => {
            if aspect > 1.0 {
                "x"
            } else {
                "y"
            }
        }
        other => other,
    };
    let t = (fov_degrees.to_radians() / 2.0).tan();
    let tan_x = match axis {
        "x" => t,
        "y" => t * aspect,
        "diagonal" => t * w / (w * w + h * h).sqrt(),
        _ => return None,
    };
    Some(2.0 * tan_x.atan().to_degrees())
}

impl<'a> Loader<'a> {
    /// A `<sensor>`: the camera and its film.
    pub(crate) fn sensor(&mut self, node: &'a Node) -> Result<(CameraDesc, FilmDesc), SceneError> {
        let p = Plugin::new(node)?;
        let mut film = None;
        for object in &p.objects {
            if self.is_medium(object) {
                object.take();
                self.media.camera = Some(self.medium_index(object.node)?);
                continue;
            }
            match object.node.tag.as_str() {
                "film" => {
                    object.take();
                    if film.is_some() {
                        return Err(object.node.pos.error("more than one <film> in a sensor"));
                    }
                    film = Some(self.film(object.node)?);
                }
                "sampler" => {
                    object.take();
                    self.sampler(object.node)?;
                }
                _ => {}
            }
        }
        let film = film.unwrap_or(FilmDesc { width: DEFAULT_FILM.0, height: DEFAULT_FILM.1, filter: default_filter() });
        let m = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let frame_error = || p.error("'to_world' is degenerate (forward or up axis collapses)");
        let forward = normalize(m.vector([0.0, 0.0, 1.0])).ok_or_else(frame_error)?;
        let up0 = m.vector([0.0, 1.0, 0.0]);
        let d = dot(up0, forward);
        let up = normalize([up0[0] - d * forward[0], up0[1] - d * forward[1], up0[2] - d * forward[2]])
            .ok_or_else(frame_error)?;
        // Mitsuba's camera +x points to the left of the image.
        let left = m.vector([1.0, 0.0, 0.0]);
        let mut right = cross(forward, up);
        if dot(right, left) > 0.0 {
            right = right.map(|v| -v);
        }
        let position = m.point([0.0; 3]);
        p.ignore(&["near_clip", "far_clip"]);
        let projection = match p.ty.as_str() {
            "perspective" | "thinlens" => {
                let fov = self.field_of_view(&p, &film)?;
                if p.ty == "perspective" {
                    p.ignore(&["focus_distance"]);
                    Projection::Perspective { horizontal_fov_degrees: fov as f32 }
                } else {
                    let aperture_radius = p.float_or("aperture_radius", 0.03)?;
                    let focus_distance = p.float_required("focus_distance")?;
                    if !positive(aperture_radius) {
                        return Err(p.error(format!("'aperture_radius' must be positive, got {aperture_radius}")));
                    }
                    if !positive(focus_distance) {
                        return Err(p.error(format!("'focus_distance' must be positive, got {focus_distance}")));
                    }
                    Projection::ThinLens {
                        horizontal_fov_degrees: fov as f32,
                        aperture_radius: aperture_radius as f32,
                        focus_distance: focus_distance as f32,
                    }
                }
            }
            "orthographic" => {
                // Mitsuba's orthographic camera sees camera-space x ∈ [-1, 1] and
                // y ∈ [-1/aspect, 1/aspect]; to_world's scale sets the extent.
                let sx = length(m.vector([1.0, 0.0, 0.0]));
                let sy = length(up0);
                if (sx - sy).abs() > 1e-4 * sx {
                    self.warnings.push(format!(
                        "{}: {}: 'to_world' scales x ({sx}) and y ({sy}) differently; the width follows x and \
                         the height the film's aspect ratio",
                        node.pos.location(),
                        p.what()
                    ));
                }
                if !positive(sx) {
                    return Err(frame_error());
                }
                Projection::Orthographic { width: (2.0 * sx) as f32 }
            }
            other => return Err(p.error(format!("unsupported sensor type '{other}'"))),
        };
        p.finish(&mut self.warnings);
        let camera = CameraDesc {
            position: to_vec3(position),
            forward: to_vec3(forward),
            up: to_vec3(up),
            right: to_vec3(right),
            projection,
        };
        Ok((camera, film))
    }

    /// The horizontal field of view (degrees) from `fov` + `fov_axis` or `focal_length`.
    pub(crate) fn field_of_view(&mut self, p: &Plugin, film: &FilmDesc) -> Result<f64, SceneError> {
        let fov = p.float("fov")?;
        let focal = p.string("focal_length")?;
        let axis = p.string("fov_axis")?.map(str::to_ascii_lowercase);
        let (fov, axis) = match (fov, focal) {
            (Some(_), Some(_)) => return Err(p.error("give either 'fov' or 'focal_length', not both")),
            (Some(f), None) => (f, axis.unwrap_or_else(|| "x".into())),
            (None, focal) => {
                // 35 mm film equivalent: the focal length gives the diagonal field of view.
                let text = focal.unwrap_or("50mm");
                let mm: f64 = text
                    .trim()
                    .trim_end_matches("mm")
                    .trim()
                    .parse()
                    .map_err(|_| p.error(format!("bad focal_length '{text}' (expected e.g. '50mm')")))?;
                if !positive(mm) {
                    return Err(p.error(format!("focal_length must be positive, got '{text}'")));
                }
                let diagonal = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
                (2.0 * (diagonal / (2.0 * mm)).atan().to_degrees(), "diagonal".to_string())
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(p.error(format!("'fov' must be in (0, 180) degrees, got {fov}")));
        }
        horizontal_fov(fov, &axis, film.width, film.height)
            .ok_or_else(|| p.error(format!("unknown fov_axis '{axis}' (expected x, y, diagonal, smaller or larger)")))
    }

    /// A `<film>`.
    fn film(&mut self, node: &'a Node) -> Result<FilmDesc, SceneError> {
        let p = Plugin::new(node)?;
        if p.ty == "ldrfilm" {
            return Err(p.error(super::xml::old_format("film 'ldrfilm'")));
        }
        if p.ty != "hdrfilm" {
            return Err(p.error(format!("unsupported film type '{}'", p.ty)));
        }
        let dimension = |name: &str, default: u32| -> Result<u32, SceneError> {
            match p.integer(name)? {
                None => Ok(default),
                Some(v) if (1..=1 << 16).contains(&v) => Ok(v as u32),
                Some(v) => Err(p.error(format!("'{name}' must be between 1 and 65536, got {v}"))),
            }
        };
        let width = dimension("width", DEFAULT_FILM.0)?;
        let height = dimension("height", DEFAULT_FILM.1)?;
        let mut filter = None;
        for object in &p.objects {
            if object.node.tag == "rfilter" {
                object.take();
                if filter.is_some() {
                    return Err(object.node.pos.error("more than one <rfilter> in a film"));
                }
                filter = Some(self.rfilter(object.node)?);
            }
        }
        p.ignore(&["pixel_format", "component_format", "file_format", "banner", "high_quality_edges"]);
        p.finish(&mut self.warnings);
        Ok(FilmDesc { width, height, filter: filter.unwrap_or_else(default_filter) })
    }

    /// An `<rfilter>`.
    fn rfilter(&mut self, node: &'a Node) -> Result<FilterDesc, SceneError> {
        let p = Plugin::new(node)?;
        let positive = |name: &str, v: f64| -> Result<f32, SceneError> {
            if v > 0.0 && v.is_finite() {
                Ok(v as f32)
            } else {
                Err(p.error(format!("'{name}' must be positive, got {v}")))
            }
        };
        let filter = match p.ty.as_str() {
            "box" => {
                if let Some(r) = p.float("radius")?
                    && (r - 0.5).abs() > 1e-6
                {
                    let error = p.error(format!("rfilter 'box': radius {r} is not supported (only 0.5)"));
                    self.unsupported(error, "0.5 pixel used")?;
                }
                FilterDesc::Box
            }
            "tent" => FilterDesc::Tent { radius: positive("radius", p.float_or("radius", 1.0)?)? },
            "gaussian" => {
                let stddev = positive("stddev", p.float_or("stddev", 0.5)?)?;
                let radius = positive("radius", p.float_or("radius", 4.0 * f64::from(stddev))?)?;
                FilterDesc::Gaussian { stddev, radius }
            }
            other => return Err(p.error(format!("unsupported rfilter type '{other}'"))),
        };
        p.finish(&mut self.warnings);
        Ok(filter)
    }

    /// A `<sampler>` (in the `<sensor>` or at the top level): only its `sample_count` is used
    /// (returned in [`RenderSettings`](crate::RenderSettings); the sampler type changes the
    /// noise, not the expected image). A second sampler is an error.
    pub(crate) fn sampler(&mut self, node: &'a Node) -> Result<(), SceneError> {
        let p = Plugin::new(node)?;
        if self.settings.samples_per_pixel.is_some() {
            return Err(p.error("a second <sampler> (only one sample count can apply)"));
        }
        // Mitsuba's default sample count is 4.
        let count = p.integer("sample_count")?.unwrap_or(4);
        let count = u32::try_from(count)
            .ok()
            .filter(|&c| c > 0)
            .ok_or_else(|| p.error(format!("'sample_count' {count} must be ≥ 1")))?;
        self.settings.samples_per_pixel = Some(count);
        p.ignore(&["seed", "jitter", "strength", "scramble_seed", "dimension", "sample_dimension"]);
        p.finish(&mut self.warnings);
        Ok(())
    }

    /// An `<integrator>`: its maximum path length, `rr_depth` and `hide_emitters` are used.
    /// `aov` and `moment` wrap other integrators: the first nested `<integrator>` gives the
    /// depth and `rr_depth`.
    pub(crate) fn integrator(&mut self, node: &'a Node) -> Result<(), SceneError> {
        if self.integrator_seen {
            self.warnings.push(format!("{}: second <integrator> ignored", node.pos.location()));
            return Ok(());
        }
        self.integrator_seen = true;
        self.max_path_length = self.integrator_depth(node)?;
        if self.max_path_length == Some(0) {
            self.warnings.push(format!(
                "{}: max_depth 0: no light reaches the camera (the image is black)",
                node.pos.location()
            ));
        }
        Ok(())
    }

    /// The path length in segments of `node` and of the integrators it wraps.
    fn integrator_depth(&mut self, node: &'a Node) -> Result<Option<u32>, SceneError> {
        let p = Plugin::new(node)?;
        let max_depth = p.integer("max_depth")?;
        let depth = match max_depth {
            None | Some(-1) => None,
            Some(d) if d < -1 => return Err(p.error(format!("'max_depth' must be -1 (unlimited) or ≥ 0, got {d}"))),
            Some(d) => Some(u32::try_from(d).map_err(|_| p.error(format!("'max_depth' {d} is too large")))?),
        };
        let where_ = node.pos.location();
        let result = match p.ty.as_str() {
            "path" | "volpath" | "volpathmis" | "bdpt" | "ptracer" | "prb" | "prbvolpath" => {
                if let Some(rr_depth) = p.integer("rr_depth")? {
                    // Mitsuba 3 refuses rr_depth ≤ 0 too.
                    let start = u32::try_from(rr_depth).ok().filter(|&d| d >= 1).ok_or_else(|| {
                        let pos = p.prop("rr_depth").map_or_else(|| node.pos.clone(), |q| q.pos.clone());
                        pos.error(format!("{}: 'rr_depth' must be an integer ≥ 1, got {rr_depth}", p.what()))
                    })?;
                    self.settings.rr_depth = Some(start);
                }
                depth
            }
            "direct" => {
                self.warnings.push(format!(
                    "{where_}: integrator 'direct' is rendered as paths of at most 2 segments (direct lighting)"
                ));
                p.ignore(&["emitter_samples", "bsdf_samples", "shading_samples"]);
                Some(2)
            }
            "aov" | "moment" => {
                let nested = p.objects.iter().find(|o| o.node.tag == "integrator");
                self.warnings.push(format!(
                    "{where_}: integrator '{}' is not supported; only the image of the integrator it wraps is rendered",
                    p.ty
                ));
                p.ignore(&["aovs"]);
                match nested {
                    Some(inner) => {
                        for o in p.objects.iter().filter(|o| o.node.tag == "integrator") {
                            o.take();
                        }
                        self.integrator_depth(inner.node)?
                    }
                    None => depth,
                }
            }
            other => {
                let error = p.error(format!("integrator '{other}' is not supported"));
                self.unsupported(error, "rendered with its max_depth by the chosen algorithm")?;
                depth
            }
        };
        if p.boolean_or("hide_emitters", false)? {
            let pos = p.prop("hide_emitters").map_or_else(|| node.pos.clone(), |q| q.pos.clone());
            self.unsupported(
                pos.error(format!("{}: 'hide_emitters' true is not supported by the renderer", p.what())),
                "emitters stay visible",
            )?;
            self.settings.hide_emitters = true;
        }
        p.ignore(&["rr_depth", "samples_per_pass", "timeout"]);
        p.finish(&mut self.warnings);
        Ok(result)
    }
}
