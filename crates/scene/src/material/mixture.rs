//! The BSDF of every material but the reference one: a weighted sum of leaf models (more than
//! one only for blends; two-sided materials pick a side), oriented by the shading normal. This
//! layer owns the shading frame, the geometric/shading side tests and the shading-normal
//! correction (see the module documentation of [`super`]), the component and lobe selection,
//! and the Russian-roulette continuation probability (the largest channel of the blended
//! albedo, at most 1). All pdfs it returns are solid-angle densities including the component
//! and lobe selection probabilities; delta lobes report their selection probability.

use math::{PdfW, Vec3};
use spectrum::Rgb;

use super::MAX_COMPONENTS;
use super::description::Material;
use super::diffuse::Diffuse;
use super::dispatch::Model;
use super::lobe::Sampled;
use super::map_adapter::MapAdapter;
use super::query::{BsdfEval, BsdfSample, PdfPair};
use super::shading::{FixedFrame, ShadingPoint, TransportMode, consistent, oriented_shading_normal, sides_allowed};
use crate::texture::TexturePoint;

/// The BSDF of every material but [`Material::Reference`]: a weighted sum of leaf models
/// (more than one only for blends), oriented by the shading normal.
#[derive(Clone, Copy, Debug)]
pub(super) struct ModelBsdf {
    /// Directions need not lie on the same side of the geometric and the shading tangent
    /// planes (a material that is one leaf model which follows its shading normal alone,
    /// [`super::dispatch::LeafModel::follows_shading_normal`]: [`sides_allowed`]).
    relaxed: bool,
    /// Shading frame, geometric normal and fixed direction.
    pub(super) at: FixedFrame,
    /// The hit's tangent ([`ShadingPoint::tangent`]), to rebuild the frame about another normal.
    tangent: Vec3,
    /// A normal- or bump-mapped material's per-query adapter (see [`super::map_adapter`]).
    adapter: Option<MapAdapter>,
    /// Whether `frame` uses the adapter's mirrored normal.
    flipped: bool,
    pub(super) continuation: f32,
    /// Total selection probability of the non-delta lobes.
    pub(super) non_delta_probability: f32,
    /// Total selection probability of the delta lobes.
    pub(super) delta_probability: f32,
    count: usize,
    components: [Component; MAX_COMPONENTS],
}

/// One leaf material of a [`ModelBsdf`].
#[derive(Clone, Copy, Debug)]
struct Component {
    model: Model,
    /// Product of the blend weights on the way to this leaf.
    scale: f32,
    /// Probability of choosing this component when sampling (independent of the directions).
    probability: f32,
    /// 1, or −1 for the back side of a two-sided material (the local z axis is mirrored).
    side: f32,
    /// Selection probabilities of the model's lobes for the fixed direction (not including
    /// `probability`).
    lobes: [f32; 2],
}

impl Component {
    /// Unnormalised probability of choosing this component when `w` (in the model's frame) is
    /// the fixed direction: blend weight times the model's selection weight, 0 from behind a
    /// one-sided model.
    #[inline]
    fn selection_weight(&self, w: Vec3) -> f32 {
        if self.model.one_sided() && w.z <= 0.0 { 0.0 } else { self.scale * self.model.selection_weight() }
    }

    /// Shading-frame coordinates → the model's coordinates (and back: the map is its own
    /// inverse).
    #[inline]
    fn orient(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.x, v.y, v.z * self.side)
    }
}

impl ModelBsdf {
    /// The BSDF of `material` at `point` for the unit `fixed` direction, handed to `wrap`
    /// (`None` when it cannot scatter). Always inlined into its one caller
    /// (`Bsdf::new_model`), which wraps it into the `Bsdf` it returns: without an
    /// `Option<ModelBsdf>` in between, the several-hundred-byte value is copied once, not twice.
    #[inline(always)]
    pub(super) fn build<T>(
        material: &Material,
        point: &ShadingPoint,
        fixed: Vec3,
        mode: TransportMode,
        hero: Option<f32>,
        wrap: impl FnOnce(ModelBsdf) -> T,
    ) -> Option<T> {
        let geometric = point.geometric_normal;
        let mut shading = oriented_shading_normal(point);
        // A perturbed normal is mirrored for a camera-side direction below it (in importance
        // mode: for a fixed direction that cannot scatter about it, see `evaluate`).
        let adapter = match material {
            Material::NormalMap { options, .. } | Material::BumpMap { options, .. } => {
                Some(MapAdapter::new(geometric, shading, *options))
            }
            _ => None,
        };
        let flipped = match (adapter, mode) {
            (Some(a), TransportMode::Radiance) => a.flips_for(fixed),
            (Some(a), TransportMode::Importance) => a.sampler_flips_for(fixed),
            (None, _) => false,
        };
        if let Some(a) = adapter {
            shading = a.normal(flipped);
        }
        let at = FixedFrame::new(point, shading, fixed, mode);
        // A material that is one leaf model is that model alone; some follow their shading
        // normal alone (`LeafModel::follows_shading_normal`, `sides_allowed`).
        let uv = TexturePoint { uv: point.uv, attribute: point.attribute };
        let leaf = Model::from_leaf(material, uv, hero, None);
        let relaxed = leaf.is_some_and(|m| m.follows_shading_normal());
        if !sides_allowed(relaxed, at.cos_fixed_geometric, at.local_fixed.z) {
            return None;
        }
        let empty = Component {
            model: Model::Diffuse(Diffuse { reflectance: Rgb::BLACK }),
            scale: 0.0,
            probability: 0.0,
            side: 1.0,
            lobes: [0.0; 2],
        };
        let mut bsdf = ModelBsdf {
            at,
            relaxed,
            tangent: point.tangent,
            adapter,
            flipped,
            continuation: 0.0,
            non_delta_probability: 0.0,
            delta_probability: 0.0,
            count: 0,
            components: [empty; MAX_COMPONENTS],
        };
        match leaf {
            Some(model) => bsdf.push(Some(model), 1.0, 1.0),
            None => bsdf.add(material, uv, 1.0, 1.0, hero),
        }
        bsdf.select_lobes()?;
        Some(wrap(bsdf))
    }

    /// The lobe and component selection probabilities and the continuation probability for
    /// the fixed direction; `None` when nothing can be selected.
    fn select_lobes(&mut self) -> Option<()> {
        let local_fixed = self.at.local_fixed;
        let bsdf = self;
        bsdf.delta_probability = 0.0;
        bsdf.non_delta_probability = 0.0;
        let mut total_weight = 0.0;
        let mut albedo = Rgb::BLACK;
        for c in &mut bsdf.components[..bsdf.count] {
            let w = c.orient(local_fixed);
            let (lobes, model_albedo) = c.model.lobes_and_albedo(w);
            c.lobes = lobes;
            albedo += model_albedo * c.scale;
            c.probability = c.selection_weight(w);
            total_weight += c.probability;
        }
        if !positive(total_weight) {
            return None;
        }
        for c in &mut bsdf.components[..bsdf.count] {
            c.probability /= total_weight;
            for (i, p) in c.lobes.iter().enumerate() {
                if c.model.lobe_is_delta(i) {
                    bsdf.delta_probability += c.probability * p;
                } else {
                    bsdf.non_delta_probability += c.probability * p;
                }
            }
        }
        bsdf.continuation = albedo.max_component().min(1.0);
        if !positive(bsdf.continuation) {
            return None;
        }
        Some(())
    }

    /// This BSDF about the adapter's perturbed normal, mirrored when `flipped` (two-sided
    /// materials keep the side chosen at construction); `None` without an adapter or when the
    /// fixed direction cannot scatter about that normal.
    fn reframed(&self, flipped: bool) -> Option<ModelBsdf> {
        let adapter = self.adapter?;
        let mut bsdf = *self;
        bsdf.at.frame = ShadingPoint::frame(adapter.normal(flipped), self.tangent);
        bsdf.at.local_fixed = bsdf.at.frame.to_local(self.at.fixed);
        if !consistent(self.at.cos_fixed_geometric, bsdf.at.local_fixed.z) {
            return None;
        }
        bsdf.flipped = flipped;
        bsdf.at.flat = false;
        bsdf.select_lobes()?;
        Some(bsdf)
    }

    /// Adds the leaves of `material` with blend weight `scale`, on side `side`.
    fn add(&mut self, material: &Material, uv: TexturePoint, scale: f32, side: f32, hero: Option<f32>) {
        if !positive(scale) {
            return;
        }
        match material {
            Material::Blend { weight, first, second } => {
                let w = weight.eval_at(uv).r;
                let w = if w.is_nan() { 0.0 } else { w.clamp(0.0, 1.0) };
                self.add(first, uv, scale * (1.0 - w), side, hero);
                self.add(second, uv, scale * w, side, hero);
            }
            Material::TwoSided { front, back } => {
                if self.at.local_fixed.z * side < 0.0 {
                    self.add(back.as_deref().unwrap_or(front), uv, scale, -side, hero);
                } else {
                    self.add(front, uv, scale, side, hero);
                }
            }
            // The hit's shading normal is already perturbed (see `perturb.rs`).
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => {
                self.add(nested, uv, scale, side, hero);
            }
            Material::TexturedRoughness { alpha_u, alpha_v, remap, nested } => {
                let alpha = |t: &crate::texture::Texture| {
                    let a = t.eval_at(uv).luminance().max(0.0);
                    if *remap { a.sqrt() } else { a }
                };
                self.push(Model::from_leaf(nested, uv, hero, Some((alpha(alpha_u), alpha(alpha_v)))), scale, side);
            }
            leaf => self.push(Model::from_leaf(leaf, uv, hero, None), scale, side),
        }
    }

    /// Adds a leaf model (if any) with blend weight `scale`, on side `side`.
    fn push(&mut self, model: Option<Model>, scale: f32, side: f32) {
        if self.count < MAX_COMPONENTS
            && let Some(model) = model
        {
            self.components[self.count] = Component { model, scale, probability: 0.0, side, lobes: [0.0; 2] };
            self.count += 1;
        }
    }

    /// Evaluates the BSDF for `generated`. With a map adapter, the camera-side direction picks
    /// the normal and the light-side one the shadowing factor, so that both transport modes
    /// evaluate one BSDF. The sampler in importance mode keeps only directions whose normal is
    /// the one it sampled about (the unmirrored one when the fixed direction can scatter
    /// about it), so the forward pdf there, and the reverse pdf in radiance mode, are zero for
    /// directions that would pick the other normal.
    /// The null transmission of the whole mixture for its fixed direction: the blend-weighted
    /// sum of its components' ([`super::dispatch::LeafModel::null_transmission`]), when every
    /// component has one; `None` otherwise.
    pub(super) fn null_transmission(&self) -> Option<Rgb> {
        let mut sum = Rgb::BLACK;
        for c in &self.components[..self.count] {
            sum += c.model.null_transmission(c.orient(self.at.local_fixed))? * c.scale;
        }
        Some(sum)
    }

    pub(super) fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        let Some(adapter) = self.adapter else { return self.evaluate_in_frame(generated) };
        match self.at.mode {
            TransportMode::Radiance => {
                let mut eval = self.evaluate_in_frame(generated)?;
                if adapter.sampler_flips_for(generated) != self.flipped {
                    eval.pdf.reverse = PdfW(0.0);
                }
                eval.value *= adapter.shadowing(generated);
                Some(eval)
            }
            TransportMode::Importance => {
                let flipped = adapter.flips_for(generated);
                let mut eval = if flipped == self.flipped {
                    self.evaluate_in_frame(generated)?
                } else {
                    let mut eval = self.reframed(flipped)?.evaluate_in_frame(generated)?;
                    eval.pdf.forward = PdfW(0.0);
                    eval
                };
                eval.value *= adapter.shadowing(self.at.fixed);
                Some(eval)
            }
        }
    }

    /// [`Self::evaluate`] in this BSDF's shading frame, without the map adapter.
    fn evaluate_in_frame(&self, generated: Vec3) -> Option<BsdfEval> {
        if self.non_delta_probability <= 0.0 {
            return None;
        }
        let cos_geometric = generated.dot(self.at.geometric);
        let local = self.at.frame.to_local(generated);
        if !consistent(cos_geometric, local.z) {
            return None;
        }
        // Component probabilities when the generated direction is the fixed one (they differ
        // from the stored ones only by the one-sided components, which do not scatter from
        // behind).
        let mut reverse_total = 0.0;
        if self.count > 1 {
            for c in &self.components[..self.count] {
                reverse_total += c.selection_weight(c.orient(local));
            }
        }
        let mut value = Rgb::BLACK;
        let mut pdf = PdfPair::default();
        for c in &self.components[..self.count] {
            let fixed = c.orient(self.at.local_fixed);
            let generated = c.orient(local);
            let e = c.model.evaluate_generated(fixed, generated, self.at.mode, c.lobes);
            value += e.value * c.scale;
            pdf.forward.0 += c.probability * e.forward;
            let reverse_probability = if self.count == 1 {
                1.0
            } else if reverse_total > 0.0 {
                c.selection_weight(generated) / reverse_total
            } else {
                0.0
            };
            pdf.reverse.0 += reverse_probability * e.reverse;
        }
        if value.is_black() || !value.is_finite() {
            return None;
        }
        Some(BsdfEval {
            value: value * self.at.shading_factor(local.z, cos_geometric),
            cos_generated: cos_geometric.abs(),
            pdf,
        })
    }

    /// Samples a lobe (all lobes, or only the delta lobes when `specular_only`).
    pub(super) fn sample(&self, u: [f32; 3], specular_only: bool) -> Option<BsdfSample> {
        let total = if specular_only { self.delta_probability } else { 1.0 };
        if !positive(total) {
            return None;
        }
        // Walk the lobes with u[2]; keep the last candidate for rounding at the end.
        let mut pick = u[2] * total;
        let mut chosen = None;
        'search: for (index, c) in self.components[..self.count].iter().enumerate() {
            for (lobe, p) in c.lobes.iter().enumerate() {
                let probability = c.probability * p;
                if !positive(probability) || (specular_only && !c.model.lobe_is_delta(lobe)) {
                    continue;
                }
                chosen = Some((index, lobe, probability, pick));
                if pick < probability {
                    break 'search;
                }
                pick -= probability;
            }
        }
        let (index, lobe, probability, pick) = chosen?;
        let c = &self.components[index];
        let rescaled = (pick / probability).clamp(0.0, ONE_MINUS_EPSILON);
        let sampled = c.model.sample(c.orient(self.at.local_fixed), lobe, [u[0], u[1], rescaled], self.at.mode)?;
        match sampled {
            Sampled::Lobe { direction, lobe } => {
                let direction = self.at.frame.to_world(c.orient(direction)).normalize();
                BsdfSample::of_lobe(direction, self.evaluate(direction)?, lobe)
            }
            Sampled::Delta { direction, rho, lobe } => {
                let local = c.orient(direction);
                let world = self.at.frame.to_world(local).normalize();
                let cos_geometric = world.dot(self.at.geometric);
                if !sides_allowed(self.relaxed, cos_geometric, local.z) || rho.is_black() {
                    return None;
                }
                let mut value = rho * (c.scale * self.at.shading_factor(local.z, cos_geometric) / local.z.abs());
                match (self.adapter, self.at.mode) {
                    (None, _) => {}
                    (Some(a), TransportMode::Radiance) => value *= a.shadowing(world),
                    (Some(a), TransportMode::Importance) => {
                        if a.flips_for(world) != self.flipped {
                            return None;
                        }
                        value *= a.shadowing(self.at.fixed);
                    }
                }
                let pdf = PdfW(probability / total);
                Some(BsdfSample {
                    direction: world,
                    value,
                    cos_generated: cos_geometric.abs(),
                    pdf: PdfPair { forward: pdf, reverse: pdf },
                    lobe,
                    dispersive: c.model.dispersive(),
                })
            }
        }
    }
}

/// `x > 0` (false for NaN).
#[inline]
pub(super) fn positive(x: f32) -> bool {
    x > 0.0
}

/// The largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
