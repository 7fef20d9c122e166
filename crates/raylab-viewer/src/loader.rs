//! Loading a scene and building its kd-tree and MBVH (and DACRT's triangle copy) on a background thread, so the window keeps drawing (and the
//! current scene stays usable) while a large model loads; a failure leaves the current scene in place.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use raylab_bench::args::SceneArgs;
use raylab_core::dacrt::Dacrt;
use raylab_core::kdtree::{KdBuildError, KdParams, KdStats, KdTree};
use raylab_core::mbvh::Mbvh;
use raylab_core::method::Method;
use raylab_core::scene::{Camera, PointLight, Scene};

/// The kd-tree cost models a scene's trees are built with: one for the single-ray methods (the thesis's)
/// and one for the packet methods ([`KdParams::for_method`]), each with the command line's changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeParams {
    /// The tree of single rays (mono, and the MBVH and DACRT methods' kd-tree walks: edge-width and
    /// sampled shadows).
    pub thesis: KdParams,
    /// The tree of packets, frustum, MFT, cone and MFT over cones.
    pub packets: KdParams,
}

impl TreeParams {
    /// The parameters of the tree that `method` walks.
    pub fn for_method(&self, method: Method) -> &KdParams {
        if method.uses_packets() { &self.packets } else { &self.thesis }
    }
}

/// A built kd-tree and what the panel shows of it.
pub struct BuiltTree {
    /// The tree.
    pub tree: KdTree,
    /// Seconds its build took.
    pub build_s: f64,
    /// Its size and quality.
    pub stats: KdStats,
}

impl BuiltTree {
    fn build(scene: &Scene, params: &KdParams) -> Result<Self, KdBuildError> {
        let tree = KdTree::build(scene, params)?;
        Ok(Self { build_s: tree.build_time().as_secs_f64(), stats: tree.stats(), tree })
    }
}

/// A scene ready to trace: the triangles, their kd-trees, and the view and light it opened with.
pub struct LoadedScene {
    /// Name shown in the panel: the built-in name or the file name.
    pub name: String,
    /// The scene.
    pub scene: Scene,
    /// Its kd-tree for the single-ray methods (the thesis's cost model).
    pub kd: BuiltTree,
    /// Its kd-tree for the packet methods, when their parameters differ.
    pub packet_kd: Option<BuiltTree>,
    /// The parameters of both trees (the animation rebuilds with them).
    pub params: TreeParams,
    /// Its 4-wide BVH, for the mbvh method.
    pub mbvh: Mbvh,
    /// Its triangles prepared for divide-and-conquer tracing (a copy, no structure), for the dacrt method.
    pub dacrt: Dacrt,
    /// The camera the scene opened with (the flags, the scene's default view, or a view of the whole scene).
    pub camera: Camera,
    /// The benchmark light.
    pub light: PointLight,
    /// Seconds spent loading and building.
    pub load_s: f64,
    /// What the loader worked around (missing textures and the like), each naming the file.
    pub warnings: Vec<String>,
}

impl LoadedScene {
    /// The kd-tree that `method` walks, and what the panel shows of it.
    pub fn kd_for(&self, method: Method) -> &BuiltTree {
        match &self.packet_kd {
            Some(b) if method.uses_packets() => b,
            _ => &self.kd,
        }
    }
}

/// Loads `args`' scene and builds its trees on the calling thread, reporting the stage through `stage`.
pub fn load_now(args: &SceneArgs, params: &TreeParams, stage: &dyn Fn(&str)) -> Result<LoadedScene, String> {
    let t0 = Instant::now();
    stage("loading scene");
    let progress = |done: f32| stage(&format!("loading scene {:.0}%", done * 100.0));
    let raylab_scene::Loaded { scene, warnings } =
        raylab_scene::load_with_progress(&args.source(), &progress).map_err(|e| e.to_string())?;
    let (camera, light) = args.camera_and_light(&scene)?;
    stage("building kd-tree");
    let kd = BuiltTree::build(&scene, &params.thesis).map_err(|e| format!("{}: {e}", args.scene))?;
    let packet_kd = if params.packets == params.thesis {
        None
    } else {
        stage("building the packet methods' kd-tree");
        Some(BuiltTree::build(&scene, &params.packets).map_err(|e| format!("{}: {e}", args.scene))?)
    };
    stage("building MBVH");
    let mbvh = Mbvh::build(&scene);
    let dacrt = Dacrt::new(&scene);
    let name = std::path::Path::new(&args.scene)
        .file_name()
        .map_or_else(|| args.scene.clone(), |n| n.to_string_lossy().into_owned());
    Ok(LoadedScene {
        name,
        scene,
        kd,
        packet_kd,
        params: *params,
        mbvh,
        dacrt,
        camera,
        light,
        load_s: t0.elapsed().as_secs_f64(),
        warnings,
    })
}

/// A load running on its own thread.
pub struct PendingLoad {
    /// What is being loaded (the scene flag's value).
    pub what: String,
    started: Instant,
    stage: Arc<Mutex<String>>,
    done: Receiver<Result<LoadedScene, String>>,
}

/// The state of a [`PendingLoad`] when polled.
pub enum LoadPoll {
    /// Still working.
    Running,
    /// Finished.
    Done(Box<Result<LoadedScene, String>>),
}

impl PendingLoad {
    /// Starts loading `args` with `params` on a new thread; `wake` is called when it finishes.
    pub fn start(args: SceneArgs, params: TreeParams, wake: impl Fn() + Send + 'static) -> Self {
        let stage = Arc::new(Mutex::new(String::from("starting")));
        let (tx, done) = mpsc::channel();
        let what = args.scene.clone();
        let st = Arc::clone(&stage);
        std::thread::spawn(move || {
            let set = |s: &str| {
                if let Ok(mut g) = st.lock() {
                    *g = s.to_string();
                }
            };
            // A panic in a loader must reach the user as an error, not take the viewer down.
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load_now(&args, &params, &set)))
                .unwrap_or_else(|_| Err(format!("{}: the loader failed unexpectedly", args.scene)));
            // The receiver is gone only when the viewer is closing; nothing is left to tell.
            let _ = tx.send(result);
            wake();
        });
        Self { what, started: Instant::now(), stage, done }
    }

    /// The current stage and the time so far, without taking the result.
    pub fn stage(&self) -> (String, Duration) {
        (self.stage.lock().map(|s| s.clone()).unwrap_or_default(), self.started.elapsed())
    }

    /// Where the load stands; a finished load hands its result out once.
    pub fn poll(&self) -> LoadPoll {
        match self.done.try_recv() {
            Ok(r) => LoadPoll::Done(Box::new(r)),
            Err(TryRecvError::Disconnected) => {
                LoadPoll::Done(Box::new(Err(format!("{}: the loader stopped without a result", self.what))))
            }
            Err(TryRecvError::Empty) => LoadPoll::Running,
        }
    }
}
