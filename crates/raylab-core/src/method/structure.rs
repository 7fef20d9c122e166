//! The structures methods trace through, and what a set of them is built for.

/// A structure a method traces through; [`crate::structures::Structures`] builds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Structure {
    /// The kd-tree with the thesis's cost model (thesis 2.2.1, Eq. 2.1, `c_trav` 1).
    ThesisKd,
    /// The kd-tree with the packet methods' cost model (`c_trav` [`crate::kdtree::KdParams::PACKET_C_TRAV`]).
    PacketKd,
    /// The 4-wide BVH (MBVH RS paper, section 2).
    Mbvh,
    /// The triangles prepared for divide-and-conquer tracing (seed 003).
    Dacrt,
    /// The brute-force reference.
    Reference,
}

impl Structure {
    /// The name reports and errors use.
    pub fn name(self) -> &'static str {
        match self {
            Structure::ThesisKd => "kd-tree",
            Structure::PacketKd => "packet kd-tree",
            Structure::Mbvh => "MBVH",
            Structure::Dacrt => "DACRT preparation",
            Structure::Reference => "brute-force reference",
        }
    }
}

/// What a set of structures is for: tracing rays only, or rendering frames, whose shadow techniques walk more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Closest and any hits of ray tiles (`raylab-bench trace`).
    Rays,
    /// Whole frames: also edge-width soft shadows and sampled shadows' bundles.
    Frames,
}
