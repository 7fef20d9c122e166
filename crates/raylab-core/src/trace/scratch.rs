//! Per-thread spare buffers for tile walks, so kernels called once per small tile do not allocate anew.

use std::any::Any;
use std::cell::Cell;

use raylab_simd::Vf32;

#[cfg(doc)]
use super::Tracer;
use crate::kdtree::packet::PacketStack;
use crate::packet::PacketTile;
use crate::ray::Ray;

/// The buffers of a tile's occlusion walk ([`Tracer::occluded_simd`], [`Tracer::occluded_in_proxy_simd`]),
/// kept by kernels that trace many small tiles (a point's light samples) so that each does not allocate
/// them anew (for a tile of a few samples, allocating would cost about as much as the walk).
pub(crate) struct TileScratch<V: Vf32> {
    /// Per packet, its blocked lanes.
    pub blocked: Vec<V::Mask>,
    /// The stack of packets traced alone.
    pub stack: PacketStack<V>,
    /// The tile of packets, refilled for each bundle ([`PacketTile::refill`]).
    pub tile: PacketTile<V>,
    /// Rays laid out for `tile` (edge-width walks put theirs one packet wide).
    pub rays: Vec<Option<Ray>>,
}

impl<V: Vf32> Default for TileScratch<V> {
    fn default() -> Self {
        Self { blocked: Vec::new(), stack: PacketStack::default(), tile: PacketTile::empty(), rays: Vec::new() }
    }
}

thread_local! {
    /// Each thread's spare [`TileScratch`], for the lane type it last traced a tile with.
    static SPARE_SCRATCH: Cell<Option<Box<dyn Any>>> = const { Cell::new(None) };
}

impl<V: Vf32> TileScratch<V> {
    /// This thread's spare buffers if they are for lane type `V`, else new ones: the kernels of one-tile calls
    /// ([`Tracer::intersect_tile`], [`Tracer::occluded_tile`], [`Tracer::edge_widths`],
    /// [`Tracer::occluded_in_proxy`]) would otherwise allocate a tile's packets, hits and stack for every call.
    /// A call nested in another finds none spare and allocates its own.
    pub(crate) fn take() -> Box<Self> {
        SPARE_SCRATCH.take().and_then(|spare| spare.downcast::<Self>().ok()).unwrap_or_default()
    }

    /// Leaves these buffers to the thread's next [`TileScratch::take`].
    pub(crate) fn put_back(self: Box<Self>) {
        SPARE_SCRATCH.set(Some(self));
    }
}
