//! `<shape>` plugins: meshes from files, Mitsuba's analytic rectangle, cube, sphere and disk,
//! its cylinder and `sdfgrid` as tessellated meshes (see `crate::cylinder`, `crate::sdfgrid`),
//! and instancing: a `shapegroup`
//! (shapes in their own space, referenced by id) placed by `instance` shapes with a
//! `to_world` (see `scene::instance`).

use crate::curves::{Basis, curve_mesh, read_curves};
use crate::sdfgrid::{NormalMode, read_vol, sdfgrid_mesh};
use math::{Vec2, Vec3};
use scene::desc::{Geometry, InstanceDesc, MeshData, ObjectDesc, ShapeDesc};
use scene::instance::Affine3A;

use super::Loader;
use super::Resolved;
use super::props::Plugin;
use super::transform::{Mat4, apply3, cross, dot, from_vec3, length, normalize, positive, to_vec3};
use super::xml::{Node, Pos};
use crate::scene_error::SceneError;

/// Mitsuba's `rectangle`: `[-1, 1]²` at `z = 0`, normal `+z`, uv `(0,0)` at `(-1,-1)`.
pub(crate) fn rectangle_mesh() -> MeshData {
    MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        normals: Vec::new(),
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)],
        triangles: vec![[0, 1, 2], [2, 3, 0]],
        attributes: Vec::new(),
    }
}

/// Mitsuba's `cube`: `[-1, 1]³`, four vertices per face, normals outward (by the winding), and
/// Mitsuba's uv layout: face `s`'s corners, in the order listed, get uv `(0, 1)`, `(1, 1)`,
/// `(1, 0)`, `(0, 0)`, and its triangles are corners `(0, 1, 2)` and `(3, 0, 2)`.
pub(crate) fn cube_mesh() -> MeshData {
    // Corners of each face (-y, +y, +x, +z, -x, -z), ±1 per axis.
    const FACES: [[[f32; 3]; 4]; 6] = [
        [[1., -1., -1.], [1., -1., 1.], [-1., -1., 1.], [-1., -1., -1.]],
        [[1., 1., -1.], [-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
        [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
        [[1., -1., 1.], [1., 1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
        [[-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.], [-1., -1., -1.]],
        [[1., 1., -1.], [1., -1., -1.], [-1., -1., -1.], [-1., 1., -1.]],
    ];
    const UVS: [[f32; 2]; 4] = [[0., 1.], [1., 1.], [1., 0.], [0., 0.]];
    let mut mesh = MeshData::default();
    for face in FACES {
        let base = mesh.positions.len() as u32;
        for (corner, uv) in face.iter().zip(UVS) {
            mesh.positions.push(Vec3::from_array(*corner));
            mesh.uvs.push(Vec2::from_array(uv));
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base + 3, base, base + 2]);
    }
    mesh
}

/// Applies `to_world` to an object-space mesh: positions by the matrix, normals by its inverse
/// transpose (renormalised); a mirroring transform reverses the winding so that the geometric
/// normal stays on the side of the transformed normals. `flip` reverses the winding and the
/// normals; `face_normals` drops the vertex normals.
pub(crate) fn transform_mesh(
    mut mesh: MeshData,
    m: &Mat4,
    flip: bool,
    face_normals: bool,
    pos: &Pos,
    what: &str,
    warnings: &mut Vec<String>,
) -> Result<MeshData, SceneError> {
    mesh.validate().map_err(|e| pos.error(format!("{what}: invalid mesh: {e}")))?;
    let normal_matrix = m.normal_matrix().ok_or_else(|| pos.error(format!("{what}: 'to_world' is singular")))?;
    for p in &mut mesh.positions {
        *p = to_vec3(m.point(from_vec3(*p)));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(pos.error(format!("{what}: vertex {i} is not finite after 'to_world'")));
    }
    if face_normals {
        mesh.normals.clear();
    }
    let mut normals = Vec::with_capacity(mesh.normals.len());
    for n in &mesh.normals {
        match normalize(apply3(&normal_matrix, from_vec3(*n))) {
            Some(t) => normals.push(to_vec3(if flip { t.map(|v| -v) } else { t })),
            None => {
                warnings.push(format!(
                    "{}: {what}: zero or non-finite vertex normal; vertex normals dropped",
                    pos.location()
                ));
                normals.clear();
                break;
            }
        }
    }
    mesh.normals = normals;
    if (m.det3() < 0.0) != flip {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(mesh)
}

impl<'a> Loader<'a> {
    /// A `<shape>` element.
    pub(crate) fn shape(&mut self, node: &'a Node) -> Result<(), SceneError> {
        match node.attr("type") {
            Some("shapegroup") => return self.shapegroup(node).map(|_| ()),
            Some("instance") => return self.instance(node),
            _ => {}
        }
        let p = Plugin::new(node)?;
        let to_world = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let flip = p.boolean_or("flip_normals", false)?;
        let what = p.what();
        let mut sphere_frame = None;
        let geometry = match p.ty.as_str() {
            "obj" | "ply" | "serialized" => {
                let filename = p.string_required("filename")?.to_string();
                let path = self.resolve_file(&filename, node)?;
                let mesh = match p.ty.as_str() {
                    "obj" => crate::mesh::read_obj(&path)?,
                    "ply" => crate::mesh::read_ply(&path)?,
                    _ => {
                        let index = p.integer("shape_index")?.unwrap_or(0);
                        let index = u32::try_from(index)
                            .map_err(|_| p.error(format!("'shape_index' must be non-negative, got {index}")))?;
                        crate::mesh::read_serialized(&path, index)?
                    }
                };
                let face_normals = p.boolean_or("face_normals", false)?;
                p.ignore(&["flip_tex_coords"]);
                Geometry::Mesh(transform_mesh(
                    mesh,
                    &to_world,
                    flip,
                    face_normals,
                    &node.pos,
                    &what,
                    &mut self.warnings,
                )?)
            }
            "rectangle" => Geometry::Mesh(transform_mesh(
                rectangle_mesh(),
                &to_world,
                flip,
                false,
                &node.pos,
                &what,
                &mut self.warnings,
            )?),
            "cube" => {
                let face_normals = p.boolean_or("face_normals", false)?;
                Geometry::Mesh(transform_mesh(
                    cube_mesh(),
                    &to_world,
                    flip,
                    face_normals,
                    &node.pos,
                    &what,
                    &mut self.warnings,
                )?)
            }
            "cylinder" => {
                let p0 = p.vector("p0")?.unwrap_or([0.0; 3]);
                let p1 = p.vector("p1")?.unwrap_or([0.0, 0.0, 1.0]);
                let radius = p.float_or("radius", 1.0)?;
                if !positive(radius) {
                    return Err(p.error(format!("'radius' must be positive, got {radius}")));
                }
                let axis = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
                let height = length(axis);
                let n =
                    normalize(axis).filter(|_| positive(height)).ok_or_else(|| p.error("'p0' and 'p1' coincide"))?;
                // Mitsuba: to_world · translate(p0) · frame(axis) · scale(r, r, height), the frame's
                // tangents from the branchless orthonormal basis of Duff et al. (2017).
                let sign = 1f64.copysign(n[2]);
                let a = -1.0 / (sign + n[2]);
                let b = n[0] * n[1] * a;
                let s_axis = [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
                let t_axis = [b, sign + n[1] * n[1] * a, -n[1]];
                let frame = Mat4::from_columns(
                    s_axis.map(|v| v * radius),
                    t_axis.map(|v| v * radius),
                    n.map(|v| v * height),
                    p0,
                );
                Geometry::Mesh(transform_mesh(
                    crate::cylinder::cylinder_mesh(1.0, 0.0, 1.0, std::f64::consts::TAU),
                    &to_world.mul(&frame),
                    flip,
                    false,
                    &node.pos,
                    &what,
                    &mut self.warnings,
                )?)
            }
            "sphere" => {
                let center = p.vector("center")?.unwrap_or([0.0; 3]);
                let radius = p.float_or("radius", 1.0)?;
                if !positive(radius) {
                    return Err(p.error(format!("'radius' must be positive, got {radius}")));
                }
                let m = to_world.mul(&Mat4::translate(center)).mul(&Mat4::scale([radius; 3]));
                let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|a| m.vector(a));
                let lengths = axes.map(length);
                let r = (lengths[0] + lengths[1] + lengths[2]) / 3.0;
                let tolerance = 1e-4 * r;
                let uniform = lengths.iter().all(|l| (l - r).abs() <= tolerance)
                    && dot(axes[0], axes[1]).abs() <= tolerance * r
                    && dot(axes[1], axes[2]).abs() <= tolerance * r
                    && dot(axes[0], axes[2]).abs() <= tolerance * r;
                if !uniform || !positive(r) {
                    return Err(p.error(
                        "'to_world' of a sphere must be a rotation, uniform scale and translation \
                         (non-uniform scales would make an ellipsoid)",
                    ));
                }
                // Mitsuba's uv is taken in the sphere's own axes: when to_world turns them, the
                // sphere is placed as an instance of a unit sphere (see below).
                let turned = axes.iter().enumerate().any(|(i, a)| {
                    (0..3).any(|j| {
                        let expected = if i == j { r } else { 0.0 };
                        (a[j] - expected).abs() > tolerance
                    })
                });
                if turned {
                    sphere_frame = affine(&m);
                }
                Geometry::Sphere { center: to_vec3(m.point([0.0; 3])), radius: r as f32, flip_normals: flip }
            }
            "disk" => {
                let u = to_world.vector([1.0, 0.0, 0.0]);
                let v = to_world.vector([0.0, 1.0, 0.0]);
                if normalize(cross(u, v)).is_none() {
                    return Err(p.error("'to_world' collapses the disk"));
                }
                // Mitsuba's disk normal is the inverse transpose of +z, which is u × v turned
                // around when to_world mirrors.
                let mirrored = to_world.det3() < 0.0;
                Geometry::Disk {
                    center: to_vec3(to_world.point([0.0; 3])),
                    axis_u: to_vec3(u),
                    axis_v: to_vec3(v),
                    flip_normals: flip != mirrored,
                }
            }
            ty @ ("linearcurve" | "bsplinecurve") => {
                let basis = if ty == "linearcurve" { Basis::Linear } else { Basis::BSpline };
                let filename = p.string_required("filename")?.to_string();
                let path = self.resolve_file(&filename, node)?;
                let mut curves = read_curves(&path, basis).map_err(|e| p.error(e))?;
                // Positions move with to_world; radii do not (Mitsuba's rule).
                for point in curves.iter_mut().flatten() {
                    point.0 = glam::DVec3::from(to_world.point(point.0.to_array()));
                }
                Geometry::Mesh(transform_mesh(
                    curve_mesh(&curves, basis),
                    &Mat4::IDENTITY,
                    flip,
                    false,
                    &node.pos,
                    &what,
                    &mut self.warnings,
                )?)
            }
            "sdfgrid" => {
                if flip {
                    return Err(p.error("'flip_normals' is not a parameter of Mitsuba's sdfgrid"));
                }
                let mode = match p.string("normals")?.unwrap_or("smooth") {
                    "smooth" => NormalMode::Smooth,
                    "analytic" => NormalMode::Analytic,
                    other => {
                        return Err(p.error(format!("'normals' is '{other}', expected 'smooth' or 'analytic'")));
                    }
                };
                let filename = p.string_required("filename")?.to_string();
                let path = self.resolve_file(&filename, node)?;
                let grid = read_vol(&path).map_err(|e| p.error(e))?;
                let mesh = sdfgrid_mesh(&grid, mode).map_err(|e| p.error(format!("{}: {e}", path.display())))?;
                Geometry::Mesh(transform_mesh(mesh, &to_world, false, false, &node.pos, &what, &mut self.warnings)?)
            }
            other => return Err(p.error(format!("unsupported shape type '{other}'"))),
        };

        let mut material = None;
        let mut emission = None;
        let mut interface = scene::medium::MediumInterface::default();
        for object in &p.objects {
            let child = object.node;
            if self.is_medium(object) {
                object.take();
                let index = Some(self.medium_index(child)?);
                match object.name.as_deref() {
                    Some("interior") => interface.interior = index,
                    Some("exterior") => interface.exterior = index,
                    _ => {
                        return Err(child
                            .pos
                            .error(format!("{what}: a medium must be named 'interior' or 'exterior'")));
                    }
                }
                continue;
            }
            if matches!(child.tag.as_str(), "bsdf" | "ref") && self.is_null_bsdf(child) {
                object.take();
                if material.is_some() {
                    return Err(child.pos.error(format!("{what}: more than one bsdf")));
                }
                material = Some(self.null_material());
                continue;
            }
            match child.tag.as_str() {
                "bsdf" => {
                    object.take();
                    if material.is_some() {
                        return Err(child.pos.error(format!("{what}: more than one bsdf")));
                    }
                    material = Some(self.material_for_node(child)?);
                }
                "emitter" => {
                    object.take();
                    if emission.is_some() {
                        return Err(child.pos.error(format!("{what}: more than one emitter")));
                    }
                    let radiance = match child.attr("id") {
                        Some(id) => {
                            self.attached_emitters.insert(id.to_string());
                            match self.resolve(id, child)? {
                                Resolved::AreaEmitter(r) => r,
                                _ => return Err(child.pos.error("only area emitters can be attached to shapes")),
                            }
                        }
                        None => self.area_emitter(child)?,
                    };
                    emission = Some(radiance);
                }
                "ref" => {
                    object.take();
                    let id = child.required_attr("id")?;
                    match self.resolve(id, child)? {
                        Resolved::Bsdf(_) => {
                            if material.is_some() {
                                return Err(child.pos.error(format!("{what}: more than one bsdf")));
                            }
                            material = Some(self.material_for_id(id, child)?);
                        }
                        Resolved::AreaEmitter(r) => {
                            if emission.is_some() {
                                return Err(child.pos.error(format!("{what}: more than one emitter")));
                            }
                            self.attached_emitters.insert(id.to_string());
                            emission = Some(r);
                        }
                        other => {
                            return Err(child.pos.error(format!(
                                "{what}: reference '{id}' is a {}, expected a bsdf or an area emitter",
                                other.kind()
                            )));
                        }
                    }
                }
                _ => {}
            }
        }
        if emission.is_some() && p.ty == "sdfgrid" {
            return Err(p.error("an sdfgrid cannot be an area emitter (nor in Mitsuba 3)"));
        }
        let material = match material {
            Some(m) => m,
            None => self.default_material(),
        };
        p.finish(&mut self.warnings);
        let name = node.attr("id").map(str::to_string).unwrap_or_else(|| format!("{}#{}", p.ty, self.shapes.len()));
        let emission = match emission {
            Some(e) => Some(self.attach_area_emission(e, &geometry, node)?),
            None => None,
        };
        let alpha = self.material_opacity.get(&material).cloned();
        if interface != scene::medium::MediumInterface::default() {
            if self.in_shapegroup {
                return Err(p.error("media on shapes in a shapegroup are not supported (issue #15)"));
            }
            self.media.shapes.insert(self.shapes.len() as u32, interface);
        }
        let shape = ShapeDesc { name, geometry, material, emission, alpha };
        match sphere_frame {
            // A turned sphere (no emitter, no media, not already in a shapegroup) becomes a unit
            // sphere in an object of its own, placed by an instance, so that its uv follows its
            // axes. Otherwise (and for emitters, whose uv matters only when textured) the
            // world-space sphere keeps uv in world axes.
            Some(to_world)
                if shape.emission.is_none()
                    && !self.in_shapegroup
                    && !self.media.shapes.contains_key(&(self.shapes.len() as u32)) =>
            {
                let flip_normals = matches!(shape.geometry, Geometry::Sphere { flip_normals: true, .. });
                let unit = Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals };
                let object = self.objects.len() as u32;
                let name = shape.name.clone();
                self.objects
                    .push(ObjectDesc { name: name.clone(), shapes: vec![ShapeDesc { geometry: unit, ..shape }] });
                self.instances.push(InstanceDesc { name, object, to_world });
            }
            _ => self.shapes.push(shape),
        }
        Ok(())
    }
}

impl<'a> Loader<'a> {
    /// A `shapegroup`: its shapes become an object (in their own space, placed only by
    /// instances). Built once, at its first reference or where it stands, whichever comes
    /// first; returns its object index. Emitters inside are an error, as in Mitsuba 3.
    fn shapegroup(&mut self, node: &'a Node) -> Result<u32, SceneError> {
        let id = node.attr("id");
        if let Some(&index) = id.and_then(|id| self.object_of_id.get(id)) {
            return Ok(index);
        }
        let name = id.map(str::to_string).unwrap_or_else(|| format!("shapegroup#{}", self.objects.len()));
        let world_shapes = std::mem::take(&mut self.shapes);
        self.in_shapegroup = true;
        let mut result = Ok(());
        for child in &node.children {
            result = match (child.tag.as_str(), child.attr("type")) {
                ("shape", Some("shapegroup" | "instance")) => {
                    Err(child.pos.error(format!("shapegroup '{name}': nested instancing is not supported")))
                }
                ("shape", _) => self.shape(child),
                (tag, _) => {
                    Err(child.pos.error(format!("shapegroup '{name}': <{tag}> is not allowed in a shapegroup")))
                }
            };
            if result.is_ok()
                && let Some(shape) = self.shapes.last().filter(|s| s.emission.is_some())
            {
                result = Err(child.pos.error(format!(
                    "shapegroup '{name}': shape '{}' is an emitter; instanced emitters are not supported (nor \
                     in Mitsuba 3)",
                    shape.name
                )));
            }
            if result.is_err() {
                break;
            }
        }
        let shapes = std::mem::replace(&mut self.shapes, world_shapes);
        self.in_shapegroup = false;
        result?;
        if shapes.is_empty() {
            self.warnings.push(format!("{}: shapegroup '{name}' is empty", node.pos.location()));
        }
        if id.is_none() {
            self.warnings.push(format!("{}: shapegroup without an id cannot be instanced", node.pos.location()));
        }
        let index = self.objects.len() as u32;
        self.objects.push(ObjectDesc { name, shapes });
        if let Some(id) = id {
            self.object_of_id.insert(id.to_string(), index);
        }
        Ok(index)
    }

    /// An `instance`: a `<ref>` to a shapegroup placed by `to_world`.
    fn instance(&mut self, node: &'a Node) -> Result<(), SceneError> {
        let p = Plugin::new(node)?;
        let to_world = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let what = p.what();
        let mut object = None;
        for child in &p.objects {
            if child.node.tag != "ref" {
                continue;
            }
            child.take();
            if object.is_some() {
                return Err(child.node.pos.error(format!("{what}: more than one shapegroup")));
            }
            let id = child.node.required_attr("id")?;
            let target =
                self.ids.get(id).copied().ok_or_else(|| child.node.pos.error(format!("<ref>: unknown id '{id}'")))?;
            if target.tag != "shape" || target.attr("type") != Some("shapegroup") {
                return Err(child.node.pos.error(format!("{what}: '{id}' is not a shapegroup")));
            }
            object = Some(self.shapegroup(target)?);
        }
        let object = object.ok_or_else(|| p.error("an instance needs a <ref> to a shapegroup"))?;
        p.finish(&mut self.warnings);
        let to_world = affine(&to_world).ok_or_else(|| p.error("'to_world' is singular or not finite"))?;
        let name = node.attr("id").map(str::to_string).unwrap_or_else(|| format!("instance#{}", self.instances.len()));
        self.instances.push(InstanceDesc { name, object, to_world });
        Ok(())
    }
}

/// The affine part of `m` in single precision; `None` when it is singular or not finite.
fn affine(m: &Mat4) -> Option<Affine3A> {
    let column = |c: usize| Vec3::new(m.m[0][c] as f32, m.m[1][c] as f32, m.m[2][c] as f32);
    let affine = Affine3A::from_cols(column(0).into(), column(1).into(), column(2).into(), column(3).into());
    let determinant = affine.matrix3.determinant();
    (affine.is_finite() && determinant.is_finite() && determinant != 0.0).then_some(affine)
}
