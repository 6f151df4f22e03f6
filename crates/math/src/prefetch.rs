//! The software prefetch hint: one of the workspace's two `unsafe` exceptions (the other is the
//! instruction-set dispatch, [`crate::isa`]).
//!
//! Some reads miss the cache at addresses that nothing before them lets the hardware
//! prefetcher predict, and an ordinary load issued early only moves the stall (a load that
//! misses blocks retirement wherever it is). A prefetch instruction does not: it starts the miss
//! and retires. Three users, each measured (medians of paired runs, docs/performance.md):
//!
//! - The VCM camera pass: a merge query reads a bucket start in a 4 MB table and then the light
//!   vertices of the bucket in a 36 MB store (SmallVCM's scene 1 at 512²). Hints at the hit
//!   (bucket starts), after next-event estimation (the first records of each bucket) and at the
//!   start of a camera path (the vertices of the pixel's light sub-path) take 13, 7, 7 and 3 %
//!   off the VCM iteration on SmallVCM's scenes 0–3 ("Prefetching the merge queries").
//! - Sampling an environment map: the sample reads an alias slot and four texels of 3 MB of
//!   tables at random. For next-event estimation they are hinted before the ray to the vertex
//!   is traced, with the numbers the sample will draw: 6–8 % off a `pt` render of Mitsuba's
//!   matpreview (paired medians 0.916 and 0.935; "Prefetching the environment map's next-event
//!   sample"), and about 2 % more with two texel hints instead of four (0.972–0.987). For a
//!   light sub-path's emission they are hinted one sub-path ahead: 6 % off matpreview `vcm`
//!   (0.936, 0.940), 4 % off `lt` (0.963).
//!
//! - The BVH queries: a child pushed on the traversal stack is hinted (its node's or triangle
//!   block's lines) so that its miss overlaps the visit of its nearer siblings. In trees of at
//!   least 4,096 nodes only: on a 998,000-triangle mesh closest hits gained 15 % and shadow rays
//!   21 %, and a `pt` render took 0.928 of the time (docs/bvh.md, "Hints for pushed children").
//!
//! - Both lines of a record ([`prefetch_lines`]): a 64-byte light vertex in a 16-byte aligned
//!   `Vec` spans two cache lines, and the hints above covered only the first, where the
//!   connections' first read (its path length) was not. Hinting every line it spans took 7.5,
//!   9.3, 9.1 and 3.7 % off the VCM iteration on SmallVCM's scenes 0–3 (paired medians 0.925,
//!   0.907, 0.909, 0.963; docs/performance.md, "Both lines of a light vertex").
//!
//! Those measurements are what the exception to the workspace's `unsafe_code = "deny"` rests
//! on; `.ci/run` checks that no other file allows `unsafe_code`. It lives in this bottom crate
//! so that every crate above can give hints without `unsafe` of its own.

/// Asks the processor to bring the cache line that holds `item` into every cache level.
///
/// A hint only: it changes no value the program computes, whether or not the processor acts
/// on it. A no-op on targets other than x86-64.
#[inline(always)]
pub fn prefetch<T>(item: &T) {
    hint((item as *const T).cast::<i8>());
}

/// [`prefetch`] of every cache line that `item` spans: its first byte's line and, for an item
/// that is not aligned to a 64-byte line, the lines after it up to its last byte. A record of
/// 64 bytes in a `Vec` (16-byte aligned by the allocator) spans two lines; a hint for its first
/// line alone leaves the fields in the second to miss (docs/performance.md, "Both lines of a
/// light vertex").
#[inline(always)]
pub fn prefetch_lines<T: ?Sized>(item: &T) {
    let first = (item as *const T).cast::<i8>();
    let size = std::mem::size_of_val(item);
    // Offsets into the item: 0, then the start of each following line while it is inside.
    let mut offset = 0;
    while offset < size {
        hint(first.wrapping_add(offset));
        offset = (first as usize + offset) / 64 * 64 + 64 - first as usize;
    }
}

/// The prefetch instruction for the line holding `address`, an address inside a live item or
/// at its start (`wrapping_add` forms it without dereferencing anything).
#[inline(always)]
#[allow(unsafe_code)]
fn hint(address: *const i8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` is unsafe only because it takes a raw pointer and needs SSE. The
    // pointer comes from a live reference, so it points into valid memory (a prefetch would not
    // fault even otherwise: it never dereferences architecturally), and SSE is part of the
    // x86-64 baseline that every x86-64 build of this crate targets.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(address);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}
