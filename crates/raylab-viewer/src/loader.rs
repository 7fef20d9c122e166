//! Loading a scene and building its structures (both kd-trees, the MBVH, DACRT's triangle copy) on a background
//! thread, so the window keeps drawing (and the current scene stays usable) while a large model loads; a failure
//! leaves the current scene in place.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use raylab_cli::args::SceneArgs;
use raylab_core::method::{Method, Purpose};
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::structures::{StructureParams, Structures};

/// The methods the viewer offers: every one whose entry allows live frames
/// ([`raylab_core::method::MethodEntry::not_live`]).
pub fn viewer_methods() -> impl Iterator<Item = Method> {
    Method::ALL.into_iter().filter(|m| m.entry().not_live.is_none())
}

/// A scene ready to trace: the triangles, the structures of every viewer method, and the view and light it
/// opened with.
pub struct LoadedScene {
    /// Name shown in the panel: the built-in name or the file name.
    pub name: String,
    /// The scene.
    pub scene: Scene,
    /// Its structures, for frames of every method of [`viewer_methods`].
    pub structures: Structures,
    /// The camera the scene opened with (the flags, the scene's default view, or a view of the whole scene).
    pub camera: Camera,
    /// The benchmark light.
    pub light: PointLight,
    /// Seconds spent loading and building.
    pub load_s: f64,
    /// What the loader worked around (missing textures and the like), each naming the file.
    pub warnings: Vec<String>,
}

/// Loads `args`' scene and builds its structures on the calling thread, reporting the stage through `stage`.
pub fn load_now(args: &SceneArgs, params: &StructureParams, stage: &dyn Fn(&str)) -> Result<LoadedScene, String> {
    let t0 = Instant::now();
    stage("loading scene");
    let progress = |done: f32| stage(&format!("loading scene {:.0}%", done * 100.0));
    let raylab_scene::Loaded { scene, warnings } =
        raylab_scene::load_with_progress(&args.source(), &progress).map_err(|e| e.to_string())?;
    let (camera, light) = args.camera_and_light(&scene)?;
    stage("building kd-trees, MBVH and DACRT's copy");
    let methods: Vec<Method> = viewer_methods().collect();
    let structures =
        Structures::build(&scene, &methods, Purpose::Frames, params).map_err(|e| format!("{}: {e}", args.scene))?;
    let name = std::path::Path::new(&args.scene)
        .file_name()
        .map_or_else(|| args.scene.clone(), |n| n.to_string_lossy().into_owned());
    Ok(LoadedScene { name, scene, structures, camera, light, load_s: t0.elapsed().as_secs_f64(), warnings })
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
    pub fn start(args: SceneArgs, params: StructureParams, wake: impl Fn() + Send + 'static) -> Self {
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
