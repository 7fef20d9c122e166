//! The parameters every structure of a scene is built with.

use serde::Serialize;

use crate::kdtree::KdParams;
use crate::mbvh::MbvhParams;
use crate::method::{Method, Structure};

/// How each structure is built: the two kd-tree cost models and the MBVH's spatial splits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StructureParams {
    /// The kd-tree of the single-ray methods and of the MBVH and DACRT methods' frame walks: the thesis's
    /// cost model (thesis 2.2.1, Eq. 2.1).
    pub kd: KdParams,
    /// The kd-tree of the packet, frustum, MFT, cone and MFT-over-cones methods: `c_trav`
    /// [`KdParams::PACKET_C_TRAV`] (see there why).
    pub packet_kd: KdParams,
    /// The MBVH's build.
    #[serde(skip)]
    pub mbvh: MbvhParams,
}

impl Default for StructureParams {
    fn default() -> Self {
        Self {
            kd: KdParams::default(),
            packet_kd: KdParams { c_trav: KdParams::PACKET_C_TRAV, ..KdParams::default() },
            mbvh: MbvhParams::default(),
        }
    }
}

impl StructureParams {
    /// The parameters of kd-tree `structure` ([`Structure::ThesisKd`] or [`Structure::PacketKd`]).
    pub fn kd_of(&self, structure: Structure) -> Option<&KdParams> {
        match structure {
            Structure::ThesisKd => Some(&self.kd),
            Structure::PacketKd => Some(&self.packet_kd),
            _ => None,
        }
    }

    /// The parameters of the kd-tree `method` walks ([`MethodEntry::frame_kd`](crate::method::MethodEntry::frame_kd)); the thesis's for the reference.
    pub fn kd_for(&self, method: Method) -> &KdParams {
        method.entry().frame_kd.and_then(|s| self.kd_of(s)).unwrap_or(&self.kd)
    }

    /// Checks both kd-tree parameter sets; the message names the tree and the field.
    pub fn validate(&self) -> Result<(), String> {
        self.kd.validate().map_err(|e| format!("kd-tree: {e}"))?;
        self.packet_kd.validate().map_err(|e| format!("packet kd-tree: {e}"))
    }
}
