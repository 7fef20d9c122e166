//! Everything a scene's methods trace through, built in one place: the kd-trees of both cost models, the
//! MBVH, DACRT's preparation and the brute-force reference, each only when a requested method needs it.
//!
//! [`crate::trace::Tracer::new`] is made from a [`Structures`] and refuses a method whose structures it
//! lacks; no other code assembles structures for tracing.

mod params;

pub use params::StructureParams;

use std::fmt;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::dacrt::Dacrt;
use crate::kdtree::{KdBuildError, KdStats, KdTree};
use crate::mbvh::{Mbvh, RefitError};
use crate::method::{Method, Purpose, Structure};
use crate::reference::BruteForce;
use crate::scene::Scene;

/// The structures of one scene.
pub struct Structures {
    params: StructureParams,
    thesis_kd: Option<KdTree>,
    /// `None` also when the packet methods' parameters equal the thesis's: then both share `thesis_kd`.
    packet_kd: Option<KdTree>,
    mbvh: Option<Mbvh>,
    dacrt: Option<Dacrt>,
    reference: Option<BruteForce>,
    builds: Vec<Built>,
}

/// What building one structure took.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Built {
    /// Which structure.
    #[serde(serialize_with = "structure_name")]
    pub structure: Structure,
    /// Seconds the build (or DACRT's setup) took.
    pub seconds: f64,
    /// Bytes it holds.
    pub bytes: usize,
    /// A kd-tree's size and quality.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kd: Option<KdStats>,
}

fn structure_name<S: serde::Serializer>(s: &Structure, out: S) -> Result<S::Ok, S::Error> {
    out.serialize_str(s.name())
}

/// A method asked of [`Structures`] that lack one of its structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MissingStructure {
    /// The method.
    pub method: Method,
    /// The structure it needs.
    pub structure: Structure,
}

impl fmt::Display for MissingStructure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "method '{}' needs the {}, which was not built for this run", self.method, self.structure.name())
    }
}

impl std::error::Error for MissingStructure {}

impl Structures {
    /// Builds, on the current rayon pool, every structure that `methods` need for `purpose`.
    pub fn build(
        scene: &Scene,
        methods: &[Method],
        purpose: Purpose,
        params: &StructureParams,
    ) -> Result<Self, KdBuildError> {
        let needs: Vec<Structure> = methods.iter().flat_map(|m| m.structures(purpose)).collect();
        Self::build_these(scene, &needs, params)
    }

    /// Builds, on the current rayon pool, the structures listed in `needs`.
    pub fn build_these(scene: &Scene, needs: &[Structure], params: &StructureParams) -> Result<Self, KdBuildError> {
        let mut s = Self {
            params: *params,
            thesis_kd: None,
            packet_kd: None,
            mbvh: None,
            dacrt: None,
            reference: None,
            builds: Vec::new(),
        };
        let shared = params.kd == params.packet_kd;
        let need = |x: Structure| needs.contains(&x);
        if need(Structure::ThesisKd) || (shared && need(Structure::PacketKd)) {
            s.thesis_kd = Some(s.build_kd(scene, Structure::ThesisKd)?);
        }
        if need(Structure::PacketKd) && !shared {
            s.packet_kd = Some(s.build_kd(scene, Structure::PacketKd)?);
        }
        if need(Structure::Mbvh) {
            let m = Mbvh::build_with(scene, &params.mbvh);
            let (seconds, bytes) = (m.build_time().as_secs_f64(), m.stats().bytes);
            s.builds.push(Built { structure: Structure::Mbvh, seconds, bytes, kd: None });
            s.mbvh = Some(m);
        }
        if need(Structure::Dacrt) {
            let d = Dacrt::new(scene);
            let (seconds, bytes) = (d.setup_time().as_secs_f64(), d.bytes());
            s.builds.push(Built { structure: Structure::Dacrt, seconds, bytes, kd: None });
            s.dacrt = Some(d);
        }
        if need(Structure::Reference) {
            let t = Instant::now();
            let r = BruteForce::new(scene);
            let (seconds, bytes) = (t.elapsed().as_secs_f64(), r.bytes());
            s.builds.push(Built { structure: Structure::Reference, seconds, bytes, kd: None });
            s.reference = Some(r);
        }
        Ok(s)
    }

    fn build_kd(&mut self, scene: &Scene, which: Structure) -> Result<KdTree, KdBuildError> {
        let params = self.params.kd_of(which).copied().unwrap_or_default();
        let tree = KdTree::build(scene, &params)?;
        let stats = tree.stats();
        let built = Built { structure: which, seconds: stats.build_seconds, bytes: stats.bytes, kd: Some(stats) };
        self.builds.retain(|b| b.structure != which);
        self.builds.push(built);
        Ok(tree)
    }

    /// The parameters the structures were built with.
    pub fn params(&self) -> &StructureParams {
        &self.params
    }

    /// What each build took, in build order.
    pub fn builds(&self) -> &[Built] {
        &self.builds
    }

    /// What building structure `which` took, when it was built (the shared tree for either kd-tree when
    /// their parameters are equal).
    pub fn built(&self, which: Structure) -> Option<&Built> {
        let shared = self.params.kd == self.params.packet_kd;
        let which = if shared && which == Structure::PacketKd { Structure::ThesisKd } else { which };
        self.builds.iter().find(|b| b.structure == which)
    }

    /// Seconds all builds took together.
    pub fn build_seconds(&self) -> f64 {
        self.builds.iter().map(|b| b.seconds).sum()
    }

    /// Bytes all structures hold together.
    pub fn bytes(&self) -> usize {
        self.builds.iter().map(|b| b.bytes).sum()
    }

    /// Kd-tree `which` ([`Structure::ThesisKd`] or [`Structure::PacketKd`]), when built; the two are one tree
    /// when their parameters are equal.
    pub fn kd(&self, which: Structure) -> Option<&KdTree> {
        let shared = self.params.kd == self.params.packet_kd;
        match which {
            Structure::ThesisKd => self.thesis_kd.as_ref(),
            Structure::PacketKd if shared => self.thesis_kd.as_ref(),
            Structure::PacketKd => self.packet_kd.as_ref(),
            _ => None,
        }
    }

    /// The kd-tree `method` walks ([`MethodEntry::frame_kd`](crate::method::MethodEntry::frame_kd)), when built.
    pub fn kd_for(&self, method: Method) -> Option<&KdTree> {
        self.kd(method.entry().frame_kd?)
    }

    /// The MBVH, when built.
    pub fn mbvh(&self) -> Option<&Mbvh> {
        self.mbvh.as_ref()
    }

    /// DACRT's preparation, when built.
    pub fn dacrt(&self) -> Option<&Dacrt> {
        self.dacrt.as_ref()
    }

    /// The brute-force reference, when built.
    pub fn reference(&self) -> Option<&BruteForce> {
        self.reference.as_ref()
    }

    /// True when structure `which` was built.
    pub fn has(&self, which: Structure) -> bool {
        match which {
            Structure::ThesisKd | Structure::PacketKd => self.kd(which).is_some(),
            Structure::Mbvh => self.mbvh.is_some(),
            Structure::Dacrt => self.dacrt.is_some(),
            Structure::Reference => self.reference.is_some(),
        }
    }

    /// Checks that every structure `method` needs for `purpose` is here.
    pub fn check(&self, method: Method, purpose: Purpose) -> Result<(), MissingStructure> {
        match method.structures(purpose).find(|&s| !self.has(s)) {
            Some(structure) => Err(MissingStructure { method, structure }),
            None => Ok(()),
        }
    }

    /// Follows `scene`'s moved vertices (same triangles, new positions) in every built structure, on the
    /// current rayon pool (see [`Structures::update_one`]). Returns the time each update took.
    pub fn update(&mut self, scene: &Scene) -> Result<Vec<(Structure, Duration)>, UpdateError> {
        let all = [Structure::ThesisKd, Structure::PacketKd, Structure::Mbvh, Structure::Dacrt, Structure::Reference];
        let mut times = Vec::new();
        for which in all {
            if let Some(t) = self.update_one(scene, which)? {
                times.push((which, t));
            }
        }
        Ok(times)
    }

    /// Follows `scene`'s moved vertices in structure `which`, if it was built: a kd-tree is rebuilt, the MBVH
    /// refitted (MBVH RS paper, section 4), DACRT's preparation and the reference made again (seed 003's
    /// dynamic scenes). Returns the time it took, `None` when `which` was not built (or is the packet
    /// methods' tree shared with the thesis's).
    pub fn update_one(&mut self, scene: &Scene, which: Structure) -> Result<Option<Duration>, UpdateError> {
        let t = Instant::now();
        match which {
            Structure::ThesisKd | Structure::PacketKd => {
                let thesis = which == Structure::ThesisKd;
                let built = if thesis { self.thesis_kd.is_some() } else { self.packet_kd.is_some() };
                if !built {
                    return Ok(None);
                }
                let tree = self.build_kd(scene, which).map_err(UpdateError::Kd)?;
                let elapsed = tree.build_time();
                *(if thesis { &mut self.thesis_kd } else { &mut self.packet_kd }) = Some(tree);
                return Ok(Some(elapsed));
            }
            Structure::Mbvh => match &mut self.mbvh {
                Some(m) => drop(m.refit(scene).map_err(UpdateError::Refit)?),
                None => return Ok(None),
            },
            Structure::Dacrt => match &mut self.dacrt {
                Some(d) => *d = Dacrt::new(scene),
                None => return Ok(None),
            },
            Structure::Reference => match &mut self.reference {
                Some(r) => *r = BruteForce::new(scene),
                None => return Ok(None),
            },
        }
        let elapsed = t.elapsed();
        if let Some(b) = self.builds.iter_mut().find(|b| b.structure == which) {
            b.seconds = elapsed.as_secs_f64();
        }
        Ok(Some(elapsed))
    }
}

/// Why [`Structures::update`] failed.
#[derive(Clone, Debug)]
pub enum UpdateError {
    /// A kd-tree rebuild failed.
    Kd(KdBuildError),
    /// The MBVH could not be refitted to the scene.
    Refit(RefitError),
}

impl fmt::Display for UpdateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UpdateError::Kd(e) => write!(f, "kd-tree: {e}"),
            UpdateError::Refit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for UpdateError {}
