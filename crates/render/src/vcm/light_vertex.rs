//! Compact storage of light sub-path vertices: one 64-byte record per vertex (RGB mode; 68 in
//! spectral mode) that both connections and merging read, in a flat `Vec`, plus per light
//! sub-path the index one past its last vertex. When merging is on, the records are permuted in
//! place into the range-search grid's slot order (a merge query then reads neighbouring records
//! from contiguous memory) and a slot map (4 bytes per vertex) leads a connection from a light
//! sub-path to its records.
//!
//! A record keeps what connections and merges need and the data to rebuild the vertex's BSDF
//! (material, normals, fixed direction, texture coordinates), never a BSDF. Quantised fields and
//! their error bounds (docs/architecture.md, "Light vertices"):
//! - the geometric normal, the shading normal and the fixed direction are octahedral 32-bit codes
//!   ([`math::octahedral`]): each decoded direction is within 5·10⁻⁵ rad (0.003°) of the exact one;
//! - the MIS quantities are the radius-free dVCM, cVC, cVM (§6.1, eqs. 57–61); dVC and dVM are
//!   rebuilt for the iteration's constants by eqs. 62–63 ([`SubPathMis::for_constants`]), which is
//!   exact algebra (the recursion is linear), so only float rounding differs;
//! - path length (10 bits), the termination flag (1 bit) and the Russian-roulette continuation
//!   probability share one word: the probability keeps the 21 most significant bits of its
//!   (non-negative) `f32`, i.e. the exponent and 13 mantissa bits, rounded to nearest (relative
//!   error ≤ 2⁻¹⁴ ≈ 6·10⁻⁵; 1 and 0 are exact). It enters only MIS weights (the light vertex's
//!   reverse density), where techniques that build the same path then disagree by at most that
//!   factor in one density: the weights of a path sum to 1 within 6·10⁻⁵;
//! - the material index is a full `u32` beside the record (merging does not read it).
//!
//! - texture coordinates share their 8 bytes with the mesh attribute value
//!   ([`scene::Texture::MeshAttribute`]): a vertex whose material reads a mesh attribute (such a
//!   material reads no uv texture in VCM, the driver checks) stores the attribute's three
//!   channels rounded to the 21 most significant bits of their `f32` (sign, exponent and
//!   12 mantissa bits: relative error ≤ 2⁻¹³ ≈ 1.2·10⁻⁴), others store uv exactly;
//! - a vertex whose material is anisotropic ([`scene::MaterialFlags::anisotropic`]) needs its
//!   surface tangent to rebuild the BSDF's frame: it stores the tangent's angle about the
//!   (decoded) shading normal, measured from the `x` axis of [`math::Frame::from_z`], in 16
//!   bits (error ≤ π/2¹⁶ ≈ 4.8·10⁻⁵ rad, plus the shading normal's 5·10⁻⁵ rad over the sine of
//!   the angle between ∂p/∂u and the normal, about 1 for a mesh), in the low 8
//!   mantissa bits of each of `u` and `v`, which are rounded to 16 mantissa bits for it
//!   (relative error ≤ 2⁻¹⁶ ≈ 1.5·10⁻⁵). Isotropic materials keep the exact uv and no tangent,
//!   so their vertices are unchanged; an anisotropic material that reads a mesh attribute has
//!   no bits left for the tangent and is rebuilt in the frame of `Frame::from_z` (documented
//!   deviation; no loader produces one).
//!
//! A [`LightVertex`] is its [`MergeRecord`] (what merging reads) plus normals and texture
//! coordinates; the memory-efficient mode keeps only the records.
//!
//! Everything else (position, throughput, texture coordinates) is stored at full `f32`
//! precision.

use math::{Frame, Vec2, Vec3, octahedral};
use rayon::prelude::*;
use scene::{Bsdf, Scene, ShadingPoint, TransportMode};
use spectrum::{Rgb, SpectralMode};

use super::mis::{MisConstants, SubPathMis};

/// Largest material index a light vertex can store (the top bit marks medium vertices).
pub const MAX_MATERIAL: u32 = u32::MAX >> 1;

/// The material word's flag of a medium vertex (its low bits hold the medium index).
const MEDIUM_VERTEX: u32 = 1 << 31;

/// The packed word's flag of a medium vertex: bit 31 holds bit 30 of the continuation
/// probability's `f32`, which is 0 for every probability below 2.
const IN_MEDIUM: u32 = 1 << 31;

/// Largest path length a light vertex can store (2¹⁰ − 1 segments).
pub const MAX_PATH_LENGTH: u32 = (1 << 10) - 1;

/// What merging reads of a stored light vertex, and all the memory-efficient mode keeps of it:
/// 44 bytes in RGB mode, 48 in spectral mode (four wavelengths of throughput instead of three
/// channels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeRecord<S: SpectralMode = Rgb> {
    /// Position on the surface.
    pub position: Vec3,
    /// Throughput of the light sub-path up to this vertex (emitted energy / pdfs, BSDFs and
    /// cosines of the earlier vertices).
    pub throughput: S,
    /// dVCM, cVC, cVM at this vertex.
    d_vcm: f32,
    c_vc: f32,
    c_vm: f32,
    /// Octahedral code of the fixed direction (towards the previous vertex).
    fixed: u32,
    /// Path length (bits 0–9), termination flag (bit 10), continuation probability (bits
    /// 11–31, see [`pack_continuation`]).
    packed: u32,
}

impl<S: SpectralMode> MergeRecord<S> {
    /// The MIS quantities for the constants `k` (dVC and dVM rebuilt by eqs. 62, 63).
    #[inline]
    pub fn mis(&self, k: &MisConstants) -> SubPathMis {
        SubPathMis { d_vcm: self.d_vcm, d_vc: 0.0, d_vm: 0.0, c_vc: self.c_vc, c_vm: self.c_vm }.for_constants(k)
    }

    /// Unit direction towards the previous vertex (decoded).
    #[inline]
    pub fn fixed(&self) -> Vec3 {
        octahedral::decode(self.fixed)
    }

    /// Segments from the light to this vertex.
    #[inline]
    pub fn path_length(&self) -> u32 {
        self.packed & MAX_PATH_LENGTH
    }

    /// The light sub-path kept only its hero wavelength ([`super::subpath::SubPath::terminated`]).
    #[inline]
    pub fn terminated(&self) -> bool {
        self.packed & TERMINATED != 0
    }

    /// Russian-roulette continuation probability of the vertex's BSDF (relative error ≤ 2⁻¹⁴,
    /// see the module doc).
    #[inline]
    pub fn continuation(&self) -> f32 {
        f32::from_bits(((self.packed & !IN_MEDIUM) >> CONTINUATION_SHIFT) << CONTINUATION_DROPPED_BITS)
    }

    /// Whether the vertex lies in a medium (a volume vertex, `super::medium`), not on a surface.
    #[inline]
    pub fn in_medium(&self) -> bool {
        self.packed & IN_MEDIUM != 0
    }
}

impl<S: SpectralMode> AsRef<MergeRecord<S>> for MergeRecord<S> {
    #[inline]
    fn as_ref(&self) -> &MergeRecord<S> {
        self
    }
}

/// A stored light sub-path vertex: 64 bytes in RGB mode, 68 in spectral mode. Its merging
/// record plus what only connections need to rebuild its BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightVertex<S: SpectralMode = Rgb> {
    /// What merging reads (connections read it too).
    pub record: MergeRecord<S>,
    /// Material index.
    material: u32,
    /// Octahedral codes of the geometric and the shading normal.
    normal: u32,
    shading_normal: u32,
    /// Texture coordinates (the bits of `u` and `v`), or the packed mesh attribute value (see
    /// the module doc).
    texture: [u32; 2],
}

impl<S: SpectralMode> AsRef<MergeRecord<S>> for LightVertex<S> {
    #[inline]
    fn as_ref(&self) -> &MergeRecord<S> {
        &self.record
    }
}

/// What the light pass knows of a vertex it stores.
#[derive(Clone, Copy, Debug)]
pub struct VertexData<S> {
    /// Position on the surface.
    pub position: Vec3,
    /// Throughput of the light sub-path up to the vertex.
    pub throughput: S,
    /// MIS quantities at the vertex (only dVCM, cVC and cVM are kept).
    pub mis: SubPathMis,
    /// Segments from the light to the vertex (clamped to [`MAX_PATH_LENGTH`]).
    pub path_length: u32,
    /// Material index (at most [`MAX_MATERIAL`]; the driver checks scenes).
    pub material: u32,
    /// Geometric normal.
    pub normal: Vec3,
    /// Shading normal.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// ∂p/∂u at the vertex when its material is anisotropic
    /// ([`scene::MaterialFlags::anisotropic`]), `None` otherwise.
    pub tangent: Option<Vec3>,
    /// The mesh attribute value at the vertex when its material reads one
    /// ([`scene::MaterialFlags::reads_mesh_attribute`]); it is then stored instead of `uv`.
    pub attribute: Option<Rgb>,
    /// Unit direction towards the previous vertex (the BSDF's fixed direction).
    pub fixed: Vec3,
    /// Russian-roulette continuation probability of the vertex's BSDF.
    pub continuation: f32,
    /// The light sub-path kept only its hero wavelength.
    pub terminated: bool,
}

/// Number of entries of a [`NormalCodes`] cache (a power of two).
const NORMAL_CODES: usize = 16;

/// The octahedral codes of recently stored normals, so that the light vertices on one flat
/// surface (a wall, a triangle) encode their common normal once: a direct-mapped cache keyed by
/// the normal's exact bits, whose hits return the code [`octahedral::encode`] gives, bit for bit
/// (encoding is a pure function of those bits). Keep one per sequence of light sub-paths traced
/// together (a chunk of the light pass).
#[derive(Clone, Debug, Default)]
pub struct NormalCodes {
    /// Per entry: the bits of a normal's coordinates and its code (`None`: empty).
    entries: [Option<([u32; 3], u32)>; NORMAL_CODES],
}

impl NormalCodes {
    /// `octahedral::encode(normal)`, from the cache when `normal` was encoded recently.
    #[inline]
    pub fn encode(&mut self, normal: Vec3) -> u32 {
        let bits = [normal.x.to_bits(), normal.y.to_bits(), normal.z.to_bits()];
        let mixed = (bits[0] ^ bits[1].rotate_left(11) ^ bits[2].rotate_left(22)).wrapping_mul(0x9e37_79b9);
        let entry = &mut self.entries[(mixed >> 28) as usize % NORMAL_CODES];
        match *entry {
            Some((key, code)) if key == bits => code,
            _ => {
                let code = octahedral::encode(normal);
                *entry = Some((bits, code));
                code
            }
        }
    }
}

impl<S: SpectralMode> LightVertex<S> {
    /// Packs `data` into a record.
    #[inline]
    pub fn new(data: &VertexData<S>) -> Self {
        Self::pack(data, octahedral::encode)
    }

    /// Packs `data` into a record like [`LightVertex::new`] (the same record, bit for bit),
    /// taking the codes of its normals from `codes`.
    #[inline]
    pub fn with_normal_codes(data: &VertexData<S>, codes: &mut NormalCodes) -> Self {
        Self::pack(data, |normal| codes.encode(normal))
    }

    /// Packs `data` into a record, its normals encoded by `encode_normal`
    /// ([`octahedral::encode`] or a cache of it).
    #[inline]
    fn pack(data: &VertexData<S>, mut encode_normal: impl FnMut(Vec3) -> u32) -> Self {
        let packed = data.path_length.min(MAX_PATH_LENGTH)
            | if data.terminated { TERMINATED } else { 0 }
            | pack_continuation(data.continuation) << CONTINUATION_SHIFT;
        let record = MergeRecord {
            position: data.position,
            throughput: data.throughput,
            d_vcm: data.mis.d_vcm,
            c_vc: data.mis.c_vc,
            c_vm: data.mis.c_vm,
            fixed: octahedral::encode(data.fixed),
            packed,
        };
        let normal = encode_normal(data.normal);
        // Without a shading normal both are the same vector: one encoding (the most frequent case).
        let shading_normal =
            if data.shading_normal == data.normal { normal } else { encode_normal(data.shading_normal) };
        Self {
            record,
            material: data.material.min(MAX_MATERIAL),
            normal,
            shading_normal,
            texture: match (data.attribute, data.tangent) {
                (Some(value), _) => pack_rgb(value),
                (None, Some(tangent)) => pack_uv_angle(data.uv, tangent_angle(shading_normal, tangent)),
                (None, None) => [data.uv.x.to_bits(), data.uv.y.to_bits()],
            },
        }
    }

    /// Material index (meaningless for a medium vertex, see [`LightVertex::medium`]).
    #[inline]
    pub fn material(&self) -> u32 {
        self.material
    }

    /// A vertex in medium `medium` (a volume vertex): position, throughput, MIS quantities,
    /// path length, fixed direction, continuation probability and termination flag as
    /// [`VertexData`] has them; no material, normals or texture coordinates.
    #[allow(clippy::too_many_arguments)]
    pub fn new_in_medium(
        position: Vec3,
        throughput: S,
        mis: SubPathMis,
        path_length: u32,
        medium: u32,
        fixed: Vec3,
        continuation: f32,
        terminated: bool,
    ) -> Self {
        let mut vertex = Self::new(&VertexData {
            position,
            throughput,
            mis,
            path_length,
            material: 0,
            normal: fixed,
            shading_normal: fixed,
            uv: Vec2::ZERO,
            tangent: None,
            attribute: None,
            fixed,
            continuation: continuation.min(1.0),
            terminated,
        });
        vertex.material = MEDIUM_VERTEX | (medium & MAX_MATERIAL);
        vertex.record.packed |= IN_MEDIUM;
        vertex
    }

    /// The medium index of a medium vertex, `None` on a surface.
    #[inline]
    pub fn medium(&self) -> Option<u32> {
        (self.material & MEDIUM_VERTEX != 0).then_some(self.material & MAX_MATERIAL)
    }

    /// Texture coordinates (meaningless when the material reads a mesh attribute; for an
    /// anisotropic material within a relative 2⁻¹⁵ of the exact ones, see the module doc).
    #[inline]
    pub fn uv(&self) -> Vec2 {
        Vec2::new(f32::from_bits(self.texture[0]), f32::from_bits(self.texture[1]))
    }

    /// Rebuilds the vertex's BSDF (importance transport) at the hero wavelength `hero`.
    #[inline]
    pub fn bsdf(&self, scene: &Scene, hero: Option<f32>) -> Option<Bsdf> {
        if self.medium().is_some() {
            return None;
        }
        let material = self.material;
        let shading_normal = octahedral::decode(self.shading_normal);
        let flags = scene.material_flags(material);
        let (uv, attribute, tangent) = if flags.reads_mesh_attribute {
            (Vec2::ZERO, unpack_rgb(self.texture), Vec3::ZERO)
        } else if flags.anisotropic {
            let (uv, angle) = unpack_uv_angle(self.texture);
            (uv, Rgb::BLACK, tangent_from_angle(shading_normal, angle))
        } else {
            (self.uv(), Rgb::BLACK, Vec3::ZERO)
        };
        let point =
            ShadingPoint { geometric_normal: octahedral::decode(self.normal), shading_normal, uv, tangent, attribute };
        let material = &scene.materials[self.material as usize];
        Bsdf::new_at(material, &point, self.record.fixed(), TransportMode::Importance, hero)
    }

    /// The vertex's fluorescence, if its material is fluorescent.
    #[inline]
    pub fn fluorescent<'s>(&self, scene: &'s Scene) -> Option<crate::fluorescent::FluorescentVertex<'s>> {
        let material = scene.materials.get(self.material as usize)?;
        crate::fluorescent::FluorescentVertex::at(material, self.uv())
    }
}

/// The termination flag's bit in [`MergeRecord::packed`].
const TERMINATED: u32 = 1 << 10;

/// First bit of the continuation probability's code in [`MergeRecord::packed`].
const CONTINUATION_SHIFT: u32 = 11;

/// Low mantissa bits of the continuation probability's `f32` dropped by [`pack_continuation`].
const CONTINUATION_DROPPED_BITS: u32 = 10;

/// A continuation probability (in [0, 1]) rounded to the 21 most significant bits of its `f32`
/// magnitude (exponent and 13 mantissa bits), round to nearest.
#[inline]
fn pack_continuation(probability: f32) -> u32 {
    let magnitude = probability.to_bits() & 0x7fff_ffff;
    // A carry into the exponent is correct rounding; 1.0 and 0.0 are exact.
    magnitude.saturating_add(1 << (CONTINUATION_DROPPED_BITS - 1)).min(0x7f80_0000) >> CONTINUATION_DROPPED_BITS
}

/// The angle of `tangent` about the shading normal decoded from its octahedral code
/// `normal_code`, from the `x` axis of `Frame::from_z` of that normal, as a fraction of a turn
/// in 16 bits (0 when the tangent is parallel to the normal).
#[inline]
fn tangent_angle(normal_code: u32, tangent: Vec3) -> u16 {
    let frame = Frame::from_z(octahedral::decode(normal_code));
    let angle = tangent.dot(frame.y).atan2(tangent.dot(frame.x));
    let turns = if angle.is_finite() { angle / std::f32::consts::TAU } else { 0.0 };
    ((turns * 65536.0).round() as i32).rem_euclid(65536) as u16
}

/// The unit tangent at `angle` (see [`tangent_angle`]) about the decoded shading normal.
#[inline]
fn tangent_from_angle(normal: Vec3, angle: u16) -> Vec3 {
    let frame = Frame::from_z(normal);
    let (sin, cos) = math::sin_cos_turns(angle as f32 * (1.0 / 65536.0));
    frame.x * cos + frame.y * sin
}

/// `u` and `v` rounded to 16 mantissa bits, with the angle's high byte in the low 8 bits of
/// `u` and its low byte in those of `v`.
#[inline]
fn pack_uv_angle(uv: Vec2, angle: u16) -> [u32; 2] {
    let round = |x: f32| -> u32 {
        let bits = x.to_bits();
        let magnitude = (bits & 0x7fff_ffff).saturating_add(0x80).min(0x7f7f_ff00) & !0xff;
        (bits & 0x8000_0000) | magnitude
    };
    [round(uv.x) | u32::from(angle >> 8), round(uv.y) | u32::from(angle & 0xff)]
}

/// The inverse of [`pack_uv_angle`] (up to its rounding).
#[inline]
fn unpack_uv_angle(texture: [u32; 2]) -> (Vec2, u16) {
    let uv = Vec2::new(f32::from_bits(texture[0] & !0xff), f32::from_bits(texture[1] & !0xff));
    (uv, ((texture[0] & 0xff) << 8 | (texture[1] & 0xff)) as u16)
}

/// Low bits dropped from each channel's `f32` by [`pack_rgb`].
const DROPPED_BITS: u32 = 11;

/// Three channels rounded to 21 bits each, in 63 bits.
#[inline]
fn pack_rgb(value: Rgb) -> [u32; 2] {
    let channel = |x: f32| -> u64 {
        let bits = x.to_bits();
        // Round to nearest on the magnitude (a carry into the exponent is correct rounding).
        let rounded = (bits & 0x7fff_ffff).saturating_add(1 << (DROPPED_BITS - 1)).min(0x7f80_0000);
        u64::from(((bits & 0x8000_0000) | rounded) >> DROPPED_BITS)
    };
    let packed = channel(value.r) | channel(value.g) << 21 | channel(value.b) << 42;
    [packed as u32, (packed >> 32) as u32]
}

/// The inverse of [`pack_rgb`] (up to its rounding).
#[inline]
fn unpack_rgb(texture: [u32; 2]) -> Rgb {
    let packed = u64::from(texture[0]) | u64::from(texture[1]) << 32;
    let channel = |shift: u32| f32::from_bits((((packed >> shift) & 0x1f_ffff) as u32) << DROPPED_BITS);
    Rgb::new(channel(0), channel(21), channel(42))
}

/// The vertices of one light sub-path, wherever they are stored.
#[derive(Clone, Copy, Debug)]
pub enum LightPath<'a, S: SpectralMode = Rgb> {
    /// Contiguous, in path order.
    Contiguous(&'a [LightVertex<S>]),
    /// Scattered over the store (grid slot order): the path's slots, in path order.
    Slots(&'a [LightVertex<S>], &'a [u32]),
}

impl<'a, S: SpectralMode> LightPath<'a, S> {
    /// The vertices in path order.
    #[inline]
    pub fn iter(self) -> LightPathIter<'a, S> {
        LightPathIter { path: self, next: 0 }
    }

    /// Prefetches every vertex ([`math::prefetch()`]), so that their cache misses overlap with
    /// each other and with the caller's next work instead of coming one by one at the first
    /// connections: stored in grid slot order, a path's vertices lie far apart. (Before, one
    /// loop read them all with its result kept opaque to the optimiser, which removed a third
    /// of the camera pass's self time on SmallVCM's scene 2, docs/performance.md, "Memory
    /// latency in the VCM camera pass"; a read that misses still stalls retirement, a prefetch
    /// does not.)
    #[inline]
    pub fn prefetch(self) {
        self.iter().for_each(crate::prefetch::prefetch_lines);
    }
}

/// Iterator over the vertices of a [`LightPath`], in path order.
pub struct LightPathIter<'a, S: SpectralMode> {
    path: LightPath<'a, S>,
    next: usize,
}

impl<'a, S: SpectralMode> Iterator for LightPathIter<'a, S> {
    type Item = &'a LightVertex<S>;

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        let vertex = match self.path {
            LightPath::Contiguous(vertices) => vertices.get(self.next),
            LightPath::Slots(vertices, slots) => slots.get(self.next).map(|&slot| &vertices[slot as usize]),
        };
        self.next += 1;
        vertex
    }
}

/// All light vertices of one iteration, grouped by light sub-path.
#[derive(Clone, Debug)]
pub struct LightVertexStore<S: SpectralMode = Rgb> {
    /// The vertices: light sub-path after light sub-path in path order, or, after
    /// [`LightVertexStore::permute_to_slots`], in the grid's slot order.
    pub vertices: Vec<LightVertex<S>>,
    /// For light sub-path `p`, the index one past its last vertex in path order.
    pub path_ends: Vec<u32>,
    /// Slot of the vertex of path-order index `i` (empty while the store is in path order).
    slots: Vec<u32>,
}

impl<S: SpectralMode> Default for LightVertexStore<S> {
    fn default() -> Self {
        Self { vertices: Vec::new(), path_ends: Vec::new(), slots: Vec::new() }
    }
}

impl<S: SpectralMode> LightVertexStore<S> {
    /// The vertices of light sub-path `path`.
    #[inline]
    pub fn path(&self, path: usize) -> LightPath<'_, S> {
        let start = if path == 0 { 0 } else { self.path_ends[path - 1] as usize };
        let end = self.path_ends[path] as usize;
        if self.slots.is_empty() {
            LightPath::Contiguous(&self.vertices[start..end])
        } else {
            LightPath::Slots(&self.vertices, &self.slots[start..end])
        }
    }

    /// Empties the store, keeping its allocations.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.path_ends.clear();
        self.slots.clear();
    }

    /// Moves the vertices into slot order in place: the vertex of path-order index
    /// `order[s]` goes to slot `s` (`order` is the grid's sorted index list, which may omit
    /// vertices it could not index; those take the slots after it, in path order). Keeps the
    /// slot map for [`LightVertexStore::path`]. Costs 4 bytes per vertex for the map and 4 for
    /// a transient copy that [`permute`] consumes; no second copy of the vertices.
    pub fn permute_to_slots(&mut self, order: &[u32]) {
        slot_map(self.vertices.len(), order, &mut self.slots);
        permute(&mut self.vertices, &mut self.slots.clone());
    }

    /// Bytes per stored vertex (the record; the slot map adds 4 when merging).
    pub const BYTES_PER_VERTEX: usize = std::mem::size_of::<LightVertex<S>>();
}

/// Fills `slots` with the slot of each of `n` items given the grid order `order` (item
/// `order[s]` goes to slot `s`; items missing from `order` take the slots after it, in order).
pub fn slot_map(n: usize, order: &[u32], slots: &mut Vec<u32>) {
    slots.clear();
    slots.resize(n, u32::MAX);
    for (slot, &index) in order.iter().enumerate() {
        slots[index as usize] = slot as u32;
    }
    let unindexed = slots.iter_mut().filter(|s| **s == u32::MAX);
    for (next, slot) in (order.len() as u32..).zip(unindexed) {
        *slot = next;
    }
}

/// Moves item `i` of `items` to position `dest[i]`, in place (`dest` is a permutation of
/// `0..n`, moved along with the items: it ends as the identity). The result does not depend on
/// the number of threads (it is the permutation).
pub fn permute<T: Send>(items: &mut [T], dest: &mut [u32]) {
    debug_assert_eq!(dest.len(), items.len());
    permute_range(items, dest, 0);
}

/// Items that [`permute_range`] permutes by a cycle walk: 4096 light vertices are 256 KiB,
/// within the L2 cache.
const PERMUTE_LEAF: usize = 4096;

/// Bits of the destination that one partition pass of [`permute_range`] sorts by: 16 output
/// streams, few enough for the hardware prefetcher to follow.
const PERMUTE_BITS: u32 = 4;

/// [`permute`] of items whose destinations are `base..base + n`.
///
/// A cycle walk over the whole array chases `dest` from one random position to the next, one
/// cache miss after another, on one thread (it took 32 ms of a 500-ms VCM iteration on
/// SmallVCM's scene 1, 558 k vertices). Instead, an in-place most-significant-digit radix pass
/// (American flag sort) cuts the items into at most 16 consecutive ranges by the top bits of
/// their destination: as `dest` is a permutation, range `k` receives exactly its own
/// destinations, so no counting pass is needed, and each swap puts one item into its range,
/// writing to 16 sequential streams. The ranges are then permuted the same way, in parallel,
/// down to ranges of [`PERMUTE_LEAF`] items, which stay in cache for the cycle walk.
fn permute_range<T: Send>(items: &mut [T], dest: &mut [u32], base: u32) {
    let n = items.len();
    if n <= PERMUTE_LEAF {
        for i in 0..n {
            // Swapping the item at i home brings another one to i, until i's own arrives.
            loop {
                let home = (dest[i] - base) as usize;
                if home == i {
                    break;
                }
                items.swap(i, home);
                dest.swap(i, home);
            }
        }
        return;
    }
    let bits = usize::BITS - (n - 1).leading_zeros();
    let shift = bits.saturating_sub(PERMUTE_BITS);
    let ranges = n.div_ceil(1 << shift);
    let mut heads: Vec<usize> = (0..ranges).map(|k| k << shift).collect();
    for k in 0..ranges {
        let end = ((k + 1) << shift).min(n);
        while heads[k] < end {
            let p = heads[k];
            let home = ((dest[p] - base) >> shift) as usize;
            if home == k {
                heads[k] += 1;
            } else {
                // Ranges before k are complete, so `home` > k: its next unchecked position.
                let q = heads[home];
                items.swap(p, q);
                dest.swap(p, q);
                heads[home] += 1;
            }
        }
    }
    items
        .par_chunks_mut(1 << shift)
        .zip(dest.par_chunks_mut(1 << shift))
        .enumerate()
        .for_each(|(k, (items, dest))| permute_range(items, dest, base + (k << shift) as u32));
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectrum::Hero4;

    /// The cache gives `octahedral::encode`'s code for every normal: repeated ones (hits), new
    /// ones that evict others, and ones equal as vectors but not in bits (±0).
    #[test]
    fn cached_normal_codes_are_the_encoded_ones() {
        let mut rng = math::Rng::for_stream(5, 0, 0);
        let mut codes = NormalCodes::default();
        let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z, Vec3::new(-0.0, 1.0, 0.0)];
        let random: Vec<Vec3> = (0..40)
            .map(|_| Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5).normalize())
            .collect();
        for round in 0..2000 {
            let n = if round % 3 == 0 { axes[round % axes.len()] } else { random[rng.next_u32() as usize % 40] };
            assert_eq!(codes.encode(n), octahedral::encode(n), "normal {n}");
        }
    }

    #[test]
    fn stored_vertices_keep_their_sizes() {
        // The memory estimates and the documentation quote these sizes.
        assert_eq!(std::mem::size_of::<LightVertex<Rgb>>(), 64);
        assert_eq!(std::mem::size_of::<LightVertex<Hero4>>(), 68);
        assert_eq!(std::mem::size_of::<MergeRecord<Rgb>>(), 44);
        assert_eq!(std::mem::size_of::<MergeRecord<Hero4>>(), 48);
    }

    fn data(i: u32) -> VertexData<Rgb> {
        let f = i as f32;
        VertexData {
            position: Vec3::new(f, -f, 0.5 * f),
            throughput: Rgb::new(1.0 + f, 2.0, 3.0),
            mis: SubPathMis { d_vcm: 0.25 + f, d_vc: 7.0, d_vm: 8.0, c_vc: 1.5 * f, c_vm: 2.5 },
            path_length: 1 + i % 9,
            material: i * 1000,
            normal: Vec3::new(0.3, -0.4, 0.866).normalize(),
            shading_normal: Vec3::new(0.2, -0.5, 0.8).normalize(),
            uv: Vec2::new(0.1 * f, 12.5),
            tangent: None,
            attribute: None,
            fixed: Vec3::new(-0.6, 0.0, 0.8),
            continuation: 0.75,
            terminated: i % 2 == 1,
        }
    }

    #[test]
    fn records_keep_what_they_store() {
        let k = MisConstants::new(1000, 0.01, true, true);
        for i in 0..20 {
            let d = data(i);
            let v = LightVertex::new(&d);
            let r = &v.record;
            assert_eq!((r.position, r.throughput, v.uv(), r.continuation()), (d.position, d.throughput, d.uv, 0.75));
            assert_eq!((v.material(), r.path_length(), r.terminated()), (d.material, d.path_length, d.terminated));
            assert!(r.fixed().angle_between(d.fixed) < octahedral::MAX_ANGULAR_ERROR);
            // dVC, dVM come back from cVC, cVM for any constants (eqs. 62, 63).
            let mis = r.mis(&k);
            assert_eq!(mis, d.mis.for_constants(&k));
            assert_eq!((mis.d_vcm, mis.c_vc, mis.c_vm), (d.mis.d_vcm, d.mis.c_vc, d.mis.c_vm));
        }
        // Out-of-range fields saturate instead of spilling into their neighbours.
        let d = VertexData { material: u32::MAX, path_length: 5000, terminated: false, ..data(1) };
        let v = LightVertex::new(&d);
        let r = v.record;
        assert_eq!((v.material(), r.path_length(), r.terminated()), (MAX_MATERIAL, MAX_PATH_LENGTH, false));
        assert_eq!(r.continuation(), 0.75);
        assert!(v.medium().is_none() && !r.in_medium(), "a saturated material is no medium vertex");
    }

    #[test]
    fn medium_vertices_keep_their_flag_medium_and_continuation() {
        for (i, continuation) in [0.0f32, 0.3, 0.999_99, 1.0].into_iter().enumerate() {
            let d = data(i as u32);
            let v = LightVertex::new_in_medium(d.position, d.throughput, d.mis, 7, 3, d.fixed, continuation, true);
            let r = &v.record;
            assert_eq!((v.medium(), r.in_medium(), r.path_length(), r.terminated()), (Some(3), true, 7, true));
            assert!((r.continuation() - continuation).abs() <= continuation * 6.2e-5, "{continuation}");
            assert!(r.fixed().angle_between(d.fixed) < octahedral::MAX_ANGULAR_ERROR);
            assert!(!LightVertex::new(&d).record.in_medium());
        }
    }

    /// Continuation probabilities come back within the documented relative error 2⁻¹⁴, 0 and 1
    /// exactly, without disturbing the path length and flag sharing their word; a deliberately
    /// tighter bound (2⁻¹⁵) is exceeded somewhere.
    #[test]
    fn packed_continuation_round_trips() {
        let mut worst = 0.0f64;
        let mut rng = math::Rng::for_stream(11, 0, 0);
        for i in 0..20_000u32 {
            let p = rng.uniform() * 10f32.powi(-((i % 5) as i32));
            let terminated = i % 3 == 0;
            let d = VertexData { continuation: p, path_length: MAX_PATH_LENGTH - i % 4, terminated, ..data(1) };
            let r = LightVertex::new(&d).record;
            assert_eq!((r.path_length(), r.terminated()), (d.path_length, terminated));
            if p > 0.0 {
                worst = worst.max(((r.continuation() as f64 - p as f64) / p as f64).abs());
            }
        }
        assert!(worst <= 2f64.powi(-14), "{worst}");
        assert!(worst > 2f64.powi(-15), "{worst}");
        for p in [0.0, 1.0] {
            let r = LightVertex::new(&VertexData { continuation: p, ..data(2) }).record;
            assert_eq!(r.continuation(), p);
        }
    }

    /// Mesh attribute values come back within the documented relative error 2⁻¹³, signs and
    /// zeros exactly; a deliberately coarser bound (2⁻¹⁴) is exceeded somewhere.
    #[test]
    fn packed_attributes_round_trip() {
        let mut worst = 0.0f64;
        let mut rng = math::Rng::for_stream(7, 0, 0);
        for i in 0..20_000 {
            let x = |rng: &mut math::Rng| (rng.uniform() * 2.0 - 0.5) * 10f32.powi(i % 7 - 3);
            let value = Rgb::new(x(&mut rng), x(&mut rng), x(&mut rng));
            let back = unpack_rgb(pack_rgb(value));
            for (a, b) in value.to_array().into_iter().zip(back.to_array()) {
                assert_eq!(a.is_sign_negative(), b.is_sign_negative());
                worst = worst.max(((f64::from(b) - f64::from(a)) / f64::from(a)).abs());
            }
        }
        assert!(worst <= 2f64.powi(-13), "relative error {worst}");
        assert!(worst > 2f64.powi(-14), "relative error {worst}");
        assert_eq!(unpack_rgb(pack_rgb(Rgb::new(0.0, 1.0, 0.5))), Rgb::new(0.0, 1.0, 0.5));
    }

    /// uv and a tangent angle share the texture words: uv within a relative 2⁻¹⁶, the tangent
    /// within 1.5·10⁻⁴ rad of the exact one projected into the tangent plane of the shading
    /// normal, for ∂p/∂u at least 45° from the normal (the angle's half step π/2¹⁶ plus the
    /// normal's 5·10⁻⁵ rad over sin 45°); a coarser angle (8 bits) exceeds that bound.
    #[test]
    fn packed_tangent_angles_round_trip() {
        let mut rng = math::Rng::for_stream(9, 0, 0);
        let (mut worst_uv, mut worst_angle, mut worst_coarse) = (0.0f64, 0.0f32, 0.0f32);
        for _ in 0..20_000 {
            let normal = math::warp::uniform_sphere(rng.uniform2());
            // ∂p/∂u at least 45° away from the normal (it is orthogonal to the geometric normal).
            let frame = Frame::from_z(normal);
            let phi = std::f32::consts::TAU * rng.uniform();
            let along = frame.x * phi.cos() + frame.y * phi.sin() + normal * (2.0 * rng.uniform() - 1.0);
            let tangent = along * (0.1 + 3.0 * rng.uniform());
            let uv = Vec2::new(rng.uniform() * 4.0 - 1.0, rng.uniform() * 30.0);
            let angle = tangent_angle(octahedral::encode(normal), tangent);
            let (back_uv, back_angle) = unpack_uv_angle(pack_uv_angle(uv, angle));
            assert_eq!(back_angle, angle);
            for (a, b) in [(uv.x, back_uv.x), (uv.y, back_uv.y)] {
                worst_uv = worst_uv.max(((f64::from(b) - f64::from(a)) / f64::from(a)).abs());
            }
            let decoded = octahedral::decode(octahedral::encode(normal));
            let exact = (tangent - normal * normal.dot(tangent)).normalize();
            let back = tangent_from_angle(decoded, angle);
            assert!((back.length() - 1.0).abs() < 1e-5 && back.dot(decoded).abs() < 1e-5);
            worst_angle = worst_angle.max(back.cross(exact).length());
            let coarse = tangent_from_angle(decoded, angle & 0xff00);
            worst_coarse = worst_coarse.max(coarse.cross(exact).length());
        }
        assert!(worst_uv <= 2f64.powi(-16), "uv relative error {worst_uv}");
        assert!(worst_angle < 1.5e-4, "tangent error {worst_angle} rad");
        assert!(worst_coarse > 1.5e-4, "8-bit angles: {worst_coarse} rad");
    }

    /// `permute` moves every item to its destination and leaves the destinations as the
    /// identity: sizes below, at and above the cycle walk's leaf size (4096), one radix level
    /// (10 007) and two (100 003), for random permutations, the identity and a reversal (every
    /// item in another range).
    #[test]
    fn permute_moves_every_item_home() {
        let mut rng = math::Rng::for_stream(5, 0, 0);
        for n in [0usize, 1, 2, 3, 255, 256, 257, 511, 512, 513, 4096, 10_007, 100_003] {
            let mut random: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                random.swap(i, rng.next_u32() as usize % (i + 1));
            }
            let identity: Vec<u32> = (0..n as u32).collect();
            let reversed: Vec<u32> = (0..n as u32).rev().collect();
            for dest in [random, identity, reversed] {
                // Item i carries its own index; after the move, slot dest[i] must hold i.
                let mut items: Vec<u64> = (0..n as u64).map(|i| i * 7 + 1).collect();
                let mut moved = dest.clone();
                permute(&mut items, &mut moved);
                for (i, &d) in dest.iter().enumerate() {
                    assert_eq!(items[d as usize], i as u64 * 7 + 1, "n = {n}, item {i}");
                }
                assert!(moved.iter().enumerate().all(|(i, &d)| d as usize == i), "n = {n}");
            }
        }
    }

    /// A stored vertex whose material reads a mesh attribute rebuilds the BSDF of the exact
    /// attribute value within the packing's relative error; one whose material does not keeps
    /// its uv exactly. A material reading a uv checkerboard tells the two apart.
    #[test]
    fn stored_vertices_rebuild_attribute_bsdfs() {
        use scene::{Camera, Material, Scene, Texture};
        let attribute =
            Material::Diffuse { reflectance: Texture::MeshAttribute { name: "vertex_color".into(), scale: 1.0 } };
        let checker = Material::Diffuse {
            reflectance: Texture::Checkerboard {
                color0: Rgb::splat(0.2),
                color1: Rgb::splat(0.8),
                to_uv: scene::desc::UvTransform::IDENTITY,
            },
        };
        let camera = Camera::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, Vec3::Y, 40.0, 4, 4);
        let scene = Scene::new("t", Vec::new(), vec![attribute, checker], Vec::new(), camera);
        assert!(scene.material_flags(0).reads_mesh_attribute && !scene.material_flags(1).reads_mesh_attribute);
        let generated = Vec3::new(0.3, 0.2, 0.9).normalize();
        let value = |v: &LightVertex| v.bsdf(&scene, None).unwrap().evaluate(generated).unwrap().value;
        let colour = Rgb::new(0.123_456, 0.654_321, 0.999);
        let normal = Vec3::Z;
        let d = VertexData { material: 0, normal, shading_normal: normal, attribute: Some(colour), ..data(3) };
        let d = VertexData { fixed: Vec3::new(-0.6, 0.0, 0.8), ..d };
        let exact = colour * std::f32::consts::FRAC_1_PI;
        let got = value(&LightVertex::new(&d));
        for (a, b) in got.to_array().into_iter().zip(exact.to_array()) {
            assert!(((a - b) / b).abs() <= 2f32.powi(-13), "{got:?} vs {exact:?}");
        }
        // The checker material keeps uv (0.75, 0.25): colour1, 0.8/π.
        let d = VertexData { material: 1, attribute: None, uv: Vec2::new(0.75, 0.25), ..d };
        assert!((value(&LightVertex::new(&d)).r - 0.8 * std::f32::consts::FRAC_1_PI).abs() < 1e-6);
    }

    #[test]
    fn permuting_into_slots_keeps_every_path() {
        let mut store = LightVertexStore::<Rgb>::default();
        // Three paths of 3, 0 and 4 vertices.
        for i in 0..7 {
            store.vertices.push(LightVertex::new(&data(i)));
        }
        store.path_ends = vec![3, 3, 7];
        let before: Vec<Vec<LightVertex>> = (0..3).map(|p| store.path(p).iter().copied().collect()).collect();
        // A grid order that leaves out index 4 (it then takes the last slot).
        let order = [5u32, 0, 6, 2, 1, 3];
        let original = store.vertices.clone();
        store.permute_to_slots(&order);
        for (slot, &index) in order.iter().enumerate() {
            assert_eq!(store.vertices[slot], original[index as usize]);
        }
        assert_eq!(store.vertices[6], original[4]);
        let after: Vec<Vec<LightVertex>> = (0..3).map(|p| store.path(p).iter().copied().collect()).collect();
        assert_eq!(before, after);
        assert_eq!(after[1].len(), 0);
    }
}
