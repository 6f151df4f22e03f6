//! pbrt-v4's object instancing: `ObjectBegin "name"` … `ObjectEnd` defines an object from the
//! shapes between them, `ObjectInstance "name"` places it with the current transformation.
//!
//! As in pbrt-v4, `ObjectBegin` also begins an attribute block and `ObjectEnd` ends it; the
//! shapes of the definition keep the transformation current when each was declared, and an
//! instance maps the object by the transformation current at `ObjectInstance`. Area lights in a
//! definition are an error (pbrt-v4 does not instance area lights either); nesting definitions,
//! instancing inside a definition and redefining a name are errors.

use std::path::Path;

use scene::desc::{InstanceDesc, ObjectDesc};
use scene::instance::Affine3A;

use super::parser::Directive;
use super::transform::Mat4;
use super::{Block, Builder, err};
use crate::scene_error::SceneError;

impl Builder {
    /// `ObjectBegin "name"`.
    pub(super) fn object_begin(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        self.require_world(file, d, true)?;
        let name = d.str_arg(0).to_string();
        if let Some((open, _, pos, _)) = &self.defining {
            return Err(err(
                file,
                d.pos,
                format!(
                    "ObjectBegin \"{name}\" inside the definition of \"{open}\" (begun at line {}); objects cannot be nested",
                    pos.line
                ),
            ));
        }
        if self.object_of_name.contains_key(&name) {
            return Err(err(file, d.pos, format!("ObjectBegin: object \"{name}\" is defined twice")));
        }
        self.stack.push((self.state.clone(), Block::Attribute, file.to_path_buf(), d.pos));
        let world_shapes = std::mem::take(&mut self.shapes);
        self.defining = Some((name, file.to_path_buf(), d.pos, world_shapes));
        Ok(())
    }

    /// `ObjectEnd`.
    pub(super) fn object_end(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let Some((name, begin_file, pos, world_shapes)) = self.defining.take() else {
            return Err(err(file, d.pos, "ObjectEnd without a matching ObjectBegin"));
        };
        let shapes = std::mem::replace(&mut self.shapes, world_shapes);
        match self.stack.pop() {
            Some((saved, Block::Attribute, ..)) => self.state = saved,
            _ => {
                return Err(err(file, d.pos, format!("ObjectEnd: the blocks inside object \"{name}\" are not closed")));
            }
        }
        if let Some(shape) = shapes.iter().find(|s| s.emission.is_some()) {
            return Err(err(
                &begin_file,
                pos,
                format!(
                    "object \"{name}\": shape '{}' is an area light; area lights cannot be instanced (nor in pbrt-v4)",
                    shape.name
                ),
            ));
        }
        self.object_of_name.insert(name.clone(), self.objects.len() as u32);
        self.objects.push(ObjectDesc { name, shapes });
        Ok(())
    }

    /// `ObjectInstance "name"`.
    pub(super) fn object_instance(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        self.require_world(file, d, true)?;
        let name = d.str_arg(0);
        if let Some((open, ..)) = &self.defining {
            return Err(err(file, d.pos, format!("ObjectInstance \"{name}\" inside the definition of \"{open}\"")));
        }
        let &object = self
            .object_of_name
            .get(name)
            .ok_or_else(|| err(file, d.pos, format!("ObjectInstance: unknown object \"{name}\"")))?;
        let to_world = affine(&self.state.ctm).ok_or_else(|| {
            err(file, d.pos, "ObjectInstance: the transformation is singular, projective or not finite")
        })?;
        let index = self.instances.len();
        self.instances.push(InstanceDesc { name: format!("{name}#{index}"), object, to_world });
        Ok(())
    }

    /// Errors when the file ended inside an object definition.
    pub(super) fn check_objects_closed(&self) -> Result<(), SceneError> {
        match &self.defining {
            Some((name, file, pos, _)) => {
                Err(err(file, *pos, format!("ObjectBegin \"{name}\" without a matching ObjectEnd")))
            }
            None => Ok(()),
        }
    }
}

/// The affine part of `m` in single precision; `None` when `m` is projective, singular or not
/// finite.
fn affine(m: &Mat4) -> Option<Affine3A> {
    if m.m[3] != [0.0, 0.0, 0.0, 1.0] {
        return None;
    }
    let column = |c: usize| glam_vec(m.m[0][c], m.m[1][c], m.m[2][c]);
    let affine = Affine3A::from_cols(column(0), column(1), column(2), column(3));
    let determinant = affine.matrix3.determinant();
    (affine.is_finite() && determinant.is_finite() && determinant != 0.0).then_some(affine)
}

fn glam_vec(x: f64, y: f64, z: f64) -> math::Vec3A {
    math::Vec3A::new(x as f32, y as f32, z as f32)
}
