//! A reader for NanoVDB files (`.nvdb`, the format of NanoVDB 32.x as in OpenVDB 10): the float
//! grids pbrt-v4's `nanovdb` medium reads, decoded into dense voxel arrays.
//!
//! **File** (little-endian). One or more segments, each: a 16-byte header (the magic number
//! `NanoVDB0` as a `u64`, a version `u32` packing major·2²¹ + minor·2¹⁰ + patch, a grid count
//! `u16`, a codec `u16`: 0 none, 1 ZIP, 2 Blosc), then per grid 176 bytes of metadata (its
//! in-memory size at byte 0, its size in the file at 8, type at 32, class at 36, name length
//! with the terminating NUL at 136) followed by the name, then the grids' buffers one after
//! the other. A buffer is stored as is (codec none) or as a `u64` byte count and a zlib
//! stream (ZIP).
//!
//! **Grid buffer.** The grid header (672 bytes: magic at 0, version at 16, the index-to-world
//! map at 296 — its double-precision 3×3 matrix at +88, inverse at +160 and translation at
//! +232, `world = M · index + t` — the world bounding box at 560, class at 632, value type at
//! 636), the tree header (64 bytes; the root's byte offset from the tree at +24), the root
//! (index bounding box, tile count at +24, background at +28; 64 bytes, then 32-byte tiles:
//! key `u64` at 0 with the tile's origin as 21 bits per axis of `coordinate >> 12`, x highest;
//! a signed byte offset of the child from the root at 8, 0 for a constant tile; the tile's
//! value at 20). Internal nodes of 32³ (upper) and 16³ (lower) entries: a value mask and a
//! child mask (bit `n` in `u64` word `n / 64`), then at byte 64 + 2·(mask bytes) a table of
//! 8-byte entries, each a child's signed byte offset from the node (child-mask bit set) or a
//! constant value in its first 4 bytes. Leaves hold 8³ values at byte 96. Entry `n` of a
//! node of side `2^s` covers local coordinates `(n >> 2s, (n >> s) & (2^s − 1), n & (2^s − 1))`
//! (x slowest); an entry spans 2¹² voxels per axis below the root, 2⁷ below an upper node,
//! 2³ below a lower node. A voxel without a node reads the background.
//!
//! Only float grids (value type 1) are decoded; other value types and Blosc compression are
//! errors. Every offset is checked: a malformed file is an error naming it, never a panic.

use std::io::Read;
use std::path::Path;

/// `NanoVDB0`, little-endian.
const MAGIC: u64 = 0x3042_4456_6f6e_614e;
/// The major version this reader knows (NanoVDB 32.x).
const MAJOR_VERSION: u32 = 32;
/// Bytes of a segment header.
const HEADER_BYTES: usize = 16;
/// Bytes of a grid's metadata before its name.
const META_BYTES: usize = 176;
/// Bytes of the grid header; the tree header follows.
const GRID_BYTES: usize = 672;
/// Bytes of the tree header.
const TREE_BYTES: usize = 64;
/// Bytes of the root header; the tiles follow.
const ROOT_BYTES: usize = 64;
/// Bytes of a root tile.
const TILE_BYTES: usize = 32;
/// Bytes of a leaf node; its values start at [`LEAF_VALUES`].
const LEAF_BYTES: usize = 2144;
/// Byte offset of a leaf's 512 values.
const LEAF_VALUES: usize = 96;
/// Largest dense decode accepted, in voxels (2²⁸, 1 GiB of floats).
pub const MAX_DENSE_VOXELS: u64 = 1 << 28;

/// The names of NanoVDB's value types, by type code.
const TYPE_NAMES: [&str; 20] = [
    "unknown", "float", "double", "int16", "int32", "int64", "Vec3f", "Vec3d", "mask", "half", "uint32", "bool",
    "RGBA8", "Fp4", "Fp8", "Fp16", "FpN", "Vec4f", "Vec4d", "index",
];

/// The names of NanoVDB's grid classes, by class code.
const CLASS_NAMES: [&str; 9] = [
    "unknown",
    "level set",
    "fog volume",
    "staggered",
    "point index",
    "point data",
    "topology",
    "voxel volume",
    "index",
];

/// A grid's class: what its values mean.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridClass(pub u32);

impl GridClass {
    /// Fog volume (densities), the class pbrt-v4 expects.
    pub const FOG_VOLUME: GridClass = GridClass(2);
    /// Unknown, which pbrt-v4 also accepts.
    pub const UNKNOWN: GridClass = GridClass(0);

    /// The class's name.
    pub fn name(self) -> String {
        CLASS_NAMES.get(self.0 as usize).map_or_else(|| format!("class {}", self.0), |n| n.to_string())
    }
}

/// A float grid read from a NanoVDB file: its transform, bounds and tree.
#[derive(Clone, Debug)]
pub struct FloatGrid {
    /// The grid's name.
    pub name: String,
    /// The grid's class.
    pub class: GridClass,
    /// Index → world: `world = matrix · index + translation` (row-major; world units per voxel).
    pub matrix: [[f64; 3]; 3],
    /// World → index: `index = inverse · (world − translation)` (row-major).
    pub inverse: [[f64; 3]; 3],
    /// The map's translation (world units).
    pub translation: [f64; 3],
    /// The world-space bounding box stored with the grid (min, max): the map's image of the
    /// active voxels' index box `[min, max + 1]`, axis-aligned.
    pub world_bounds: [[f64; 3]; 2],
    /// The value of voxels outside every node.
    pub background: f32,
    /// The grid's buffer.
    bytes: Vec<u8>,
    /// Byte offset of the root node in `bytes`.
    root: usize,
}

/// The grids of a NanoVDB file, by name, undecoded.
#[derive(Debug)]
pub struct NanoVdbFile {
    /// The file's bytes.
    bytes: Vec<u8>,
    /// Each grid's name, value-type code, codec, byte offset of its stored buffer, stored size
    /// and in-memory size.
    grids: Vec<GridEntry>,
}

#[derive(Clone, Debug)]
struct GridEntry {
    name: String,
    value_type: u32,
    codec: u16,
    offset: usize,
    file_size: usize,
    grid_size: usize,
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at.checked_add(2)?)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

fn i32_at(b: &[u8], at: usize) -> Option<i32> {
    u32_at(b, at).map(|v| v as i32)
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at.checked_add(8)?)?.try_into().ok()?))
}

fn f32_at(b: &[u8], at: usize) -> Option<f32> {
    u32_at(b, at).map(f32::from_bits)
}

fn f64_at(b: &[u8], at: usize) -> Option<f64> {
    u64_at(b, at).map(f64::from_bits)
}

/// The name of value type `code`.
fn type_name(code: u32) -> String {
    TYPE_NAMES.get(code as usize).map_or_else(|| format!("type {code}"), |n| n.to_string())
}

impl NanoVdbFile {
    /// Reads the segment headers and grid metadata of the NanoVDB file at `path`. Errors name
    /// the file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("{}: cannot read the NanoVDB file: {e}", path.display()))?;
        Self::parse(bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Parses the segment headers and grid metadata of a NanoVDB file's bytes.
    fn parse(bytes: Vec<u8>) -> Result<Self, String> {
        let mut grids = Vec::new();
        let mut at = 0usize;
        while at < bytes.len() {
            let b = &bytes[..];
            if b.len() - at < HEADER_BYTES {
                return Err(format!(
                    "truncated segment header at byte {at} ({} bytes left of {HEADER_BYTES})",
                    b.len() - at
                ));
            }
            let magic = u64_at(b, at).unwrap_or(0);
            if magic != MAGIC {
                if magic == MAGIC.swap_bytes() {
                    return Err("the NanoVDB file is big-endian; only little-endian files are supported".into());
                }
                let text: String =
                    b[at..at + 8].iter().map(|&c| if c.is_ascii_graphic() { c as char } else { '.' }).collect();
                return Err(format!(
                    "not a NanoVDB file: the segment at byte {at} starts with \"{text}\", expected the magic \"NanoVDB0\" (NanoVDB 32.x, OpenVDB 10)"
                ));
            }
            let version = u32_at(b, at + 8).unwrap_or(0);
            let (major, minor, patch) = (version >> 21, (version >> 10) & 0x7ff, version & 0x3ff);
            if major != MAJOR_VERSION {
                return Err(format!(
                    "NanoVDB version {major}.{minor}.{patch}: only major version {MAJOR_VERSION} is supported"
                ));
            }
            let count = u16_at(b, at + 12).unwrap_or(0) as usize;
            let codec = u16_at(b, at + 14).unwrap_or(0);
            at += HEADER_BYTES;
            let mut entries = Vec::with_capacity(count);
            for g in 0..count {
                let start = at;
                let truncated = move || format!("truncated metadata of grid {g} at byte {start}");
                let meta = b.get(at..at.checked_add(META_BYTES).ok_or_else(truncated)?).ok_or_else(truncated)?;
                let grid_size = u64_at(meta, 0).unwrap_or(0);
                let file_size = u64_at(meta, 8).unwrap_or(0);
                let value_type = u32_at(meta, 32).unwrap_or(0);
                let name_size = u32_at(meta, 136).unwrap_or(0) as usize;
                at += META_BYTES;
                let name = b.get(at..at.saturating_add(name_size)).ok_or_else(truncated)?;
                let name = String::from_utf8_lossy(name.split(|&c| c == 0).next().unwrap_or(&[])).into_owned();
                at += name_size;
                let to_usize =
                    |v: u64| usize::try_from(v).map_err(|_| format!("grid \"{name}\": size {v} is too large"));
                entries.push(GridEntry {
                    value_type,
                    codec,
                    offset: 0,
                    file_size: to_usize(file_size)?,
                    grid_size: to_usize(grid_size)?,
                    name,
                });
            }
            for entry in &mut entries {
                entry.offset = at;
                at = at.checked_add(entry.file_size).filter(|&end| end <= b.len()).ok_or_else(|| {
                    format!(
                        "truncated: grid \"{}\" needs {} bytes from byte {at}, the file has {}",
                        entry.name,
                        entry.file_size,
                        b.len()
                    )
                })?;
            }
            grids.extend(entries);
        }
        if grids.is_empty() {
            return Err("the NanoVDB file holds no grids".into());
        }
        Ok(Self { bytes, grids })
    }

    /// The names of the grids in the file, in order.
    pub fn names(&self) -> Vec<&str> {
        self.grids.iter().map(|g| g.name.as_str()).collect()
    }

    /// The first grid called `name`, decompressed; `None` when there is none. Errors for
    /// grids that are not float grids, unsupported codecs and malformed buffers.
    pub fn float_grid(&self, name: &str) -> Result<Option<FloatGrid>, String> {
        let Some(entry) = self.grids.iter().find(|g| g.name == name) else { return Ok(None) };
        let grid = || format!("grid \"{name}\"");
        if entry.value_type != 1 {
            return Err(format!(
                "{}: value type {}, only float grids are supported",
                grid(),
                type_name(entry.value_type)
            ));
        }
        if entry.grid_size as u64 > crate::gz::MAX_DECOMPRESSED_BYTES {
            return Err(format!("{}: {} bytes is too large", grid(), entry.grid_size));
        }
        let stored = &self.bytes[entry.offset..entry.offset + entry.file_size];
        let bytes = match entry.codec {
            0 => stored
                .get(..entry.grid_size)
                .ok_or_else(|| format!("{}: {} bytes stored, expected {}", grid(), stored.len(), entry.grid_size))?
                .to_vec(),
            1 => unzip(stored, entry.grid_size).map_err(|e| format!("{}: {e}", grid()))?,
            2 => {
                return Err(format!(
                    "{}: Blosc-compressed grids are not supported (only uncompressed and ZIP)",
                    grid()
                ));
            }
            c => return Err(format!("{}: unknown codec {c} (0 none, 1 ZIP, 2 Blosc)", grid())),
        };
        FloatGrid::parse(name, bytes).map(Some).map_err(|e| format!("{}: {e}", grid()))
    }
}

/// A ZIP-coded grid buffer: a `u64` byte count and that many bytes of zlib stream, inflating to
/// `size` bytes.
fn unzip(stored: &[u8], size: usize) -> Result<Vec<u8>, String> {
    let count = u64_at(stored, 0).ok_or("truncated ZIP block")?;
    let data = usize::try_from(count)
        .ok()
        .and_then(|n| stored.get(8..8usize.checked_add(n)?))
        .ok_or_else(|| format!("ZIP block of {count} bytes, {} stored", stored.len().saturating_sub(8)))?;
    let mut out = Vec::with_capacity(size);
    flate2::read::ZlibDecoder::new(data)
        .take(size as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot inflate the ZIP block: {e}"))?;
    if out.len() != size {
        return Err(format!("the ZIP block inflates to {} bytes, expected {size}", out.len()));
    }
    Ok(out)
}

impl FloatGrid {
    /// Parses a float grid's buffer (its header and root; the nodes are read when decoded).
    fn parse(name: &str, bytes: Vec<u8>) -> Result<Self, String> {
        let b = &bytes[..];
        if b.len() < GRID_BYTES + TREE_BYTES + ROOT_BYTES {
            return Err(format!("truncated grid buffer of {} bytes", b.len()));
        }
        if u64_at(b, 0) != Some(MAGIC) {
            return Err("the grid buffer does not start with the NanoVDB magic number".into());
        }
        let major = u32_at(b, 16).unwrap_or(0) >> 21;
        if major != MAJOR_VERSION {
            return Err(format!("grid version {major}.x: only {MAJOR_VERSION}.x is supported"));
        }
        let value_type = u32_at(b, 636).unwrap_or(0);
        if value_type != 1 {
            return Err(format!("value type {}, only float grids are supported", type_name(value_type)));
        }
        let class = GridClass(u32_at(b, 632).unwrap_or(0));
        let doubles =
            |at: usize, n: usize| -> Vec<f64> { (0..n).map(|i| f64_at(b, at + 8 * i).unwrap_or(0.0)).collect() };
        let rows = |v: Vec<f64>| [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]];
        let matrix = rows(doubles(296 + 88, 9));
        let inverse = rows(doubles(296 + 160, 9));
        let t = doubles(296 + 232, 3);
        let w = doubles(560, 6);
        let tree_root = u64_at(b, GRID_BYTES + 24).unwrap_or(0);
        let root = usize::try_from(tree_root)
            .ok()
            .and_then(|r| r.checked_add(GRID_BYTES))
            .filter(|&r| r.checked_add(ROOT_BYTES).is_some_and(|end| end <= b.len()))
            .ok_or_else(|| format!("root node offset {tree_root} lies outside the {}-byte grid", b.len()))?;
        let tiles = u32_at(b, root + 24).unwrap_or(0) as usize;
        if tiles.checked_mul(TILE_BYTES).and_then(|n| n.checked_add(root + ROOT_BYTES)).is_none_or(|end| end > b.len())
        {
            return Err(format!("the root's {tiles} tiles overrun the {}-byte grid", b.len()));
        }
        let background = f32_at(b, root + 28).unwrap_or(0.0);
        Ok(Self {
            name: name.to_string(),
            class,
            matrix,
            inverse,
            translation: [t[0], t[1], t[2]],
            world_bounds: [[w[0], w[1], w[2]], [w[3], w[4], w[5]]],
            background,
            root,
            bytes,
        })
    }

    /// The index bounding box of the active voxels stored with the root (inclusive min, max).
    pub fn index_bounds(&self) -> [[i32; 3]; 2] {
        let c = |i: usize| i32_at(&self.bytes, self.root + 4 * i).unwrap_or(0);
        [[c(0), c(1), c(2)], [c(3), c(4), c(5)]]
    }

    /// The values of the voxels with indices `lo + (x, y, z)`, `x < dims[0]` fastest, then `y`,
    /// then `z` (as the medium grids store them): stored values, tile values, the background
    /// elsewhere. At most [`MAX_DENSE_VOXELS`].
    pub fn dense(&self, lo: [i64; 3], dims: [usize; 3]) -> Result<Vec<f32>, String> {
        let count = dims.iter().try_fold(1u64, |c, &n| c.checked_mul(n as u64)).unwrap_or(u64::MAX);
        if count > MAX_DENSE_VOXELS {
            return Err(format!(
                "a dense grid of {}×{}×{} voxels is too large (at most {MAX_DENSE_VOXELS})",
                dims[0], dims[1], dims[2]
            ));
        }
        let hi: [i64; 3] = std::array::from_fn(|a| lo[a] + dims[a] as i64 - 1);
        let mut out = Dense { lo, hi, dims, values: vec![self.background; count as usize] };
        let b = &self.bytes[..];
        let tiles = u32_at(b, self.root + 24).unwrap_or(0) as usize;
        for t in 0..tiles {
            let at = self.root + ROOT_BYTES + t * TILE_BYTES;
            let key = u64_at(b, at).unwrap_or(0);
            let axis = |shift: u32| ((((key >> shift) & 0x1f_ffff) << 12) as u32 as i32) as i64;
            let origin = [axis(42), axis(21), axis(0)];
            if !out.overlaps(origin, 1 << 12) {
                continue;
            }
            let child = u64_at(b, at + 8).unwrap_or(0) as i64;
            if child == 0 {
                out.fill(origin, 1 << 12, f32_at(b, at + 20).unwrap_or(0.0));
            } else {
                let node = self.node_at(self.root, child, INTERNAL_BYTES[1])?;
                self.internal(node, 5, origin, &mut out)?;
            }
        }
        Ok(out.values)
    }

    /// The byte offset `from + delta` of a node of `size` bytes, checked against the buffer.
    fn node_at(&self, from: usize, delta: i64, size: usize) -> Result<usize, String> {
        (from as i64)
            .checked_add(delta)
            .and_then(|n| usize::try_from(n).ok())
            .filter(|&n| n.checked_add(size).is_some_and(|end| end <= self.bytes.len()))
            .ok_or_else(|| {
                format!("a child offset {delta} at byte {from} lies outside the {}-byte grid", self.bytes.len())
            })
    }

    /// Decodes the internal node at byte `node` of side `2^log2` entries (5: upper, 4: lower)
    /// whose first voxel is `origin`.
    fn internal(&self, node: usize, log2: u32, origin: [i64; 3], out: &mut Dense) -> Result<(), String> {
        let b = &self.bytes[..];
        let entries = 1usize << (3 * log2);
        let mask_bytes = entries / 8;
        let child_mask = node + 32 + mask_bytes;
        let table = node + 64 + 2 * mask_bytes;
        // Voxels per entry and axis: 2⁷ below an upper node, 2³ below a lower node.
        let child_log2 = if log2 == 5 { 7 } else { 3 };
        let side = 1i64 << child_log2;
        let range = |a: usize| -> (i64, i64) {
            let first = ((out.lo[a] - origin[a]).max(0)) >> child_log2;
            let last = ((out.hi[a] - origin[a]) >> child_log2).min((1 << log2) - 1);
            (first, last)
        };
        let (rx, ry, rz) = (range(0), range(1), range(2));
        for x in rx.0..=rx.1 {
            for y in ry.0..=ry.1 {
                for z in rz.0..=rz.1 {
                    let n = ((x << (2 * log2)) | (y << log2) | z) as usize;
                    let child_origin = [origin[0] + x * side, origin[1] + y * side, origin[2] + z * side];
                    let is_child = u64_at(b, child_mask + 8 * (n / 64)).unwrap_or(0) >> (n % 64) & 1 == 1;
                    let entry = table + 8 * n;
                    if is_child {
                        let delta = u64_at(b, entry).unwrap_or(0) as i64;
                        if log2 == 5 {
                            let child = self.node_at(node, delta, INTERNAL_BYTES[0])?;
                            self.internal(child, 4, child_origin, out)?;
                        } else {
                            let leaf = self.node_at(node, delta, LEAF_BYTES)?;
                            out.leaf(&b[leaf + LEAF_VALUES..leaf + LEAF_VALUES + 512 * 4], child_origin);
                        }
                    } else {
                        out.fill(child_origin, side, f32_at(b, entry).unwrap_or(0.0));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Bytes of a lower (16³) and an upper (32³) internal node.
const INTERNAL_BYTES: [usize; 2] = [33_856, 270_400];

/// A dense box of voxels being filled.
struct Dense {
    lo: [i64; 3],
    hi: [i64; 3],
    dims: [usize; 3],
    values: Vec<f32>,
}

impl Dense {
    /// Whether the cube of `side` voxels at `origin` meets the box.
    fn overlaps(&self, origin: [i64; 3], side: i64) -> bool {
        (0..3).all(|a| origin[a] <= self.hi[a] && origin[a] + side > self.lo[a])
    }

    /// Index of voxel `p` (inside the box).
    fn index(&self, p: [i64; 3]) -> usize {
        let d: [usize; 3] = std::array::from_fn(|a| (p[a] - self.lo[a]) as usize);
        (d[2] * self.dims[1] + d[1]) * self.dims[0] + d[0]
    }

    /// Sets the cube of `side` voxels at `origin` (clipped to the box) to `value`.
    fn fill(&mut self, origin: [i64; 3], side: i64, value: f32) {
        if !self.overlaps(origin, side) {
            return;
        }
        let lo: [i64; 3] = std::array::from_fn(|a| origin[a].max(self.lo[a]));
        let hi: [i64; 3] = std::array::from_fn(|a| (origin[a] + side - 1).min(self.hi[a]));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let start = self.index([lo[0], y, z]);
                let end = self.index([hi[0], y, z]);
                self.values[start..=end].fill(value);
            }
        }
    }

    /// Copies a leaf's 8³ values (`x` slowest, `z` fastest) at `origin`, clipped to the box.
    fn leaf(&mut self, values: &[u8], origin: [i64; 3]) {
        if !self.overlaps(origin, 8) {
            return;
        }
        for x in 0..8i64 {
            for y in 0..8i64 {
                for z in 0..8i64 {
                    let p = [origin[0] + x, origin[1] + y, origin[2] + z];
                    if (0..3).all(|a| (self.lo[a]..=self.hi[a]).contains(&p[a])) {
                        let n = ((x << 6) | (y << 3) | z) as usize * 4;
                        let i = self.index(p);
                        self.values[i] = f32_at(values, n).unwrap_or(0.0);
                    }
                }
            }
        }
    }
}
