//! Shapes: the `Shape` directive, meshes in world space, and `loopsubdiv` refined at load.

use std::path::Path;

use math::{Vec2, Vec3};
use scene::desc::{Geometry, MeshData, ShapeDesc};

use crate::pbrt::parser::Directive;
use crate::pbrt::tokenizer::Pos;
use crate::pbrt::transform::normalize;
use crate::scene_error::SceneError;

use super::curve;
use super::{Builder, err, f32v, resolve, similarity_scale};

impl Builder {
    pub(super) fn shape_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let ty = d.str_arg(0);
        let p = &d.params;
        let ctm = self.state.ctm;
        if !ctm.is_affine() {
            return Err(err(file, d.pos, "shapes under a projective transformation are not supported"));
        }
        let name = format!(
            "{ty} ({}:{})",
            file.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            d.pos.line
        );
        let geometry = match ty {
            "trianglemesh" | "bilinearmesh" => {
                let quads = ty == "bilinearmesh";
                let corners = if quads { 4 } else { 3 };
                let Some((positions, _)) = p.numbers("P", &["point3"], 3)? else {
                    return Err(err(file, d.pos, format!("{ty} needs \"point3 P\"")));
                };
                let count = positions.len() / 3;
                let indices = match p.ints("indices")? {
                    Some(i) => i,
                    None if count == corners => (0..corners as i64).collect(),
                    None => {
                        return Err(err(
                            file,
                            d.pos,
                            format!("{ty} needs \"integer indices\" (it has {count} vertices)"),
                        ));
                    }
                };
                let ipos = p.find("indices").map_or(d.pos, |x| x.pos);
                if indices.len() % corners != 0 {
                    return Err(p.error(ipos, format!("{} indices is not a multiple of {corners}", indices.len())));
                }
                if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= count) {
                    return Err(p.error(ipos, format!("index {bad} is out of range (there are {count} vertices)")));
                }
                let normals = p.numbers("N", &["normal3"], 3)?;
                let uvs = match p.numbers("uv", &["point2", "float"], 2)? {
                    Some(v) => Some(v),
                    None => p.numbers("st", &["point2", "float"], 2)?,
                };
                for (what, values, per) in [("N", &normals, 3), ("uv", &uvs, 2)] {
                    if let Some((v, pos)) = values
                        && v.len() / per != count
                    {
                        return Err(p.error(*pos, format!("{} values of '{what}' for {count} vertices", v.len() / per)));
                    }
                }
                let mut triangles = Vec::new();
                for c in indices.chunks(corners) {
                    let c: Vec<u32> = c.iter().map(|&i| i as u32).collect();
                    if quads {
                        // Vertices p00, p10, p01, p11: the quad's boundary is p00 p10 p11 p01.
                        triangles.push([c[0], c[1], c[3]]);
                        triangles.push([c[0], c[3], c[2]]);
                    } else {
                        triangles.push([c[0], c[1], c[2]]);
                    }
                }
                let object = MeshData {
                    positions: positions.chunks(3).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect(),
                    normals: normals.map_or_else(Vec::new, |(v, _)| {
                        v.chunks(3).map(|n| Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32)).collect()
                    }),
                    uvs: uvs.map_or_else(Vec::new, |(v, _)| {
                        v.chunks(2).map(|t| Vec2::new(t[0] as f32, t[1] as f32)).collect()
                    }),
                    triangles,
                    attributes: Vec::new(),
                };
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "plymesh" => {
                let Some((filename, fpos)) = p.string("filename")? else {
                    return Err(err(file, d.pos, "plymesh needs a \"string filename\""));
                };
                let path = resolve(file, &filename);
                if !path.is_file() {
                    return Err(p.error(fpos, format!("mesh file '{}' does not exist", path.display())));
                }
                let object = crate::mesh::read_ply(&path)?;
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "sphere" => {
                let radius = p.float("radius", 1.0)?;
                for (param, default) in [("zmin", -radius), ("zmax", radius), ("phimax", 360.0)] {
                    if let Some(x) = p.find(param)
                        && p.float(param, default)? != default
                    {
                        return Err(p.error(x.pos, format!("partial spheres ('{param}') are not supported")));
                    }
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(err(file, d.pos, format!("sphere radius {radius} must be positive")));
                }
                let scale = similarity_scale(&ctm)
                    .ok_or_else(|| err(file, d.pos, "sphere under a non-uniform scale or shear is not supported"))?;
                Geometry::Sphere {
                    center: f32v(ctm.point([0.0; 3])),
                    radius: (f64::from(radius) * scale) as f32,
                    flip_normals: self.state.reverse_orientation,
                }
            }
            "disk" => {
                let height = f64::from(p.float("height", 0.0)?);
                let radius = f64::from(p.float("radius", 1.0)?);
                if p.float("innerradius", 0.0)? != 0.0 || p.float("phimax", 360.0)? != 360.0 {
                    return Err(err(file, d.pos, "partial disks ('innerradius', 'phimax') are not supported"));
                }
                Geometry::Disk {
                    center: f32v(ctm.point([0.0, 0.0, height])),
                    axis_u: f32v(ctm.vector([radius, 0.0, 0.0])),
                    axis_v: f32v(ctm.vector([0.0, radius, 0.0])),
                    flip_normals: self.state.reverse_orientation,
                }
            }
            "cylinder" => {
                let radius = f64::from(p.float("radius", 1.0)?);
                let z_min = f64::from(p.float("zmin", -1.0)?);
                let z_max = f64::from(p.float("zmax", 1.0)?);
                let phi_max = f64::from(p.float("phimax", 360.0)?);
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(err(file, d.pos, format!("cylinder radius {radius} must be positive")));
                }
                if !(z_min.is_finite() && z_max.is_finite() && z_min != z_max) {
                    return Err(err(file, d.pos, format!("cylinder zmin {z_min} and zmax {z_max} must differ")));
                }
                if !(phi_max > 0.0 && phi_max <= 360.0) {
                    return Err(err(file, d.pos, format!("cylinder phimax {phi_max} must be in (0, 360]")));
                }
                // pbrt swaps zmin and zmax when they are reversed.
                let (z0, z1) = (z_min.min(z_max), z_min.max(z_max));
                let object = crate::cylinder::cylinder_mesh(radius, z0, z1, phi_max.to_radians());
                Geometry::Mesh(self.to_world_mesh(file, d.pos, object)?)
            }
            "loopsubdiv" => Geometry::Mesh(self.to_world_mesh(file, d.pos, loop_subdivision_mesh(file, d)?)?),
            "curve" => Geometry::Mesh(self.to_world_mesh(file, d.pos, curve::curve_mesh(p, d.pos)?)?),
            other @ ("cone" | "paraboloid" | "hyperboloid") => {
                return Err(err(file, d.arg_pos[0], format!("shape \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.arg_pos[0], format!("unknown shape type \"{other}\""))),
        };
        let material = self.current_material();
        let alpha = self.shape_alpha(p)?;
        if let (Some(_), Some(spectrum)) = (self.state.area_light, &self.state.area_light_spectrum) {
            self.emission_spectra.shapes.insert(self.shapes.len() as u32, spectrum.clone());
        }
        if let Some(texture) = &self.state.area_light_texture {
            if !matches!(geometry, Geometry::Mesh(_)) {
                return Err(err(file, d.pos, "a diffuse area light with a \"filename\" image needs a triangle mesh"));
            }
            self.emission_spectra.textures.insert(self.shapes.len() as u32, texture.clone());
        }
        let interface = self.state.medium_interface;
        if interface.interior != interface.exterior && self.defining.is_some() {
            return Err(err(file, d.pos, "media on shapes in an object definition are not supported (issue #15)"));
        }
        self.media.shape(self.shapes.len() as u32, interface);
        self.shapes.push(ShapeDesc { name, geometry, material, emission: self.state.area_light, alpha });
        self.warn_unused(p);
        Ok(())
    }

    /// Transforms an object-space mesh to world space and winds its triangles so that the
    /// right-hand-rule normal is pbrt's surface normal (module documentation).
    pub(super) fn to_world_mesh(&self, file: &Path, pos: Pos, mut mesh: MeshData) -> Result<MeshData, SceneError> {
        let ctm = self.state.ctm;
        mesh.validate().map_err(|e| err(file, pos, e))?;
        let normal_matrix = ctm.inverse().ok_or_else(|| err(file, pos, "the shape's transformation is singular"))?;
        for p in &mut mesh.positions {
            *p = f32v(ctm.point([p.x, p.y, p.z].map(f64::from)));
        }
        for n in &mut mesh.normals {
            // Normals transform with the inverse transpose.
            let m = &normal_matrix.m;
            let v = [n.x, n.y, n.z].map(f64::from);
            let t = [0, 1, 2].map(|c| m[0][c] * v[0] + m[1][c] * v[1] + m[2][c] * v[2]);
            let t = normalize(t).unwrap_or([0.0, 0.0, 1.0]);
            let t = if self.state.reverse_orientation { t.map(|c| -c) } else { t };
            *n = f32v(t);
        }
        let flip = self.state.reverse_orientation ^ (ctm.det3() < 0.0);
        let has_normals = !mesh.normals.is_empty();
        for t in &mut mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let swap = if has_normals {
                let n = mesh.normals[t[0] as usize] + mesh.normals[t[1] as usize] + mesh.normals[t[2] as usize];
                (b - a).cross(c - a).dot(n) < 0.0
            } else {
                flip
            };
            if swap {
                t.swap(1, 2);
            }
        }
        mesh.validate().map_err(|e| err(file, pos, e))?;
        Ok(mesh)
    }
}

/// pbrt's `loopsubdiv` shape (`integer levels`, default 3; `integer indices`; `point3 P`)
/// refined at load ([`crate::loop_subdivision`]).
pub(super) fn loop_subdivision_mesh(file: &Path, d: &Directive) -> Result<MeshData, SceneError> {
    let p = &d.params;
    let Some((positions, _)) = p.numbers("P", &["point3"], 3)? else {
        return Err(err(file, d.pos, "loopsubdiv needs \"point3 P\""));
    };
    let Some(indices) = p.ints("indices")? else {
        return Err(err(file, d.pos, "loopsubdiv needs \"integer indices\""));
    };
    let ipos = p.find("indices").map_or(d.pos, |x| x.pos);
    if indices.len() % 3 != 0 {
        return Err(p.error(ipos, format!("{} indices is not a multiple of 3", indices.len())));
    }
    let levels = p.ints("levels")?.map_or(Ok(3), |v| match v.as_slice() {
        [n] if *n >= 0 => Ok(*n as u32),
        _ => Err(err(file, d.pos, "loopsubdiv: \"integer levels\" must be one number >= 0")),
    })?;
    let count = positions.len() / 3;
    if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= count) {
        return Err(p.error(ipos, format!("index {bad} is out of range (there are {count} vertices)")));
    }
    let points: Vec<Vec3> = positions.chunks(3).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let triangles: Vec<[u32; 3]> = indices.chunks(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();
    crate::loop_subdivision::subdivide(&points, &triangles, levels)
        .map_err(|e| err(file, d.pos, format!("loopsubdiv: {e}")))
}
