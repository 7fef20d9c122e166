//! The renderer's diagnostic views: heat maps count exactly the work of the shaded frame (their units are
//! the pieces each method traces anyway), every method gives the same depth and normal images, and the
//! colour scales cover what the frame holds.

use raylab_core::kdtree::KdParams;
use raylab_core::method::{Method, Purpose};
use raylab_core::ray_order::RayOrder;
use raylab_core::render::{Frame, FrameView, RenderSettings, heat_color, render};
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};
use raylab_scene::builtin::{self, Detail};

const METHODS: [Method; 6] =
    [Method::Mono, Method::Packet, Method::Frustum, Method::Mft, Method::Cone, Method::MftCone];

struct Setup {
    scene: raylab_core::scene::Scene,
    /// Every method on the thesis's kd-tree (both slots take its cost model).
    structures: Structures,
}

impl Setup {
    fn new() -> Self {
        let scene = builtin::build("atrium", Detail::Test).unwrap();
        let params = StructureParams { packet_kd: KdParams::default(), ..StructureParams::default() };
        let structures = Structures::build(&scene, &METHODS, Purpose::Frames, &params).unwrap();
        Self { scene, structures }
    }

    fn frame(&self, method: Method, view: FrameView, tile: u32, heat_max: Option<f32>) -> Frame {
        let tracer = Tracer::new(&self.structures, TraceOptions { method, ..Default::default() }).unwrap();
        let settings = RenderSettings { width: 45, height: 30, tile, view, heat_max, ..Default::default() };
        let cam = self.scene.default_view().unwrap().camera;
        render(&self.scene, &tracer, &cam, self.scene.lights[0], &settings)
    }
}

#[test]
fn heat_maps_count_the_work_of_the_shaded_frame() {
    let s = Setup::new();
    for method in METHODS {
        for tile in [4, 16] {
            let shaded = s.frame(method, FrameView::Shaded, tile, None);
            for view in [FrameView::Nodes, FrameView::Isects] {
                let heat = s.frame(method, view, tile, None);
                assert_eq!(heat.stats, shaded.stats, "{method} tile {tile} {view}: different work");
                let (lo, hi) = heat.range.expect("heat maps have a scale");
                assert_eq!(lo, 0.0);
                assert!(hi > 0.0, "{method} {view}: empty heat map");
                // Every pixel has a palette colour, and the hottest one the top of the scale.
                assert!(heat.rgba.contains(&heat_color(1.0)), "{method} {view}: no pixel at the top of the scale");
            }
            assert!(shaded.range.is_none());
        }
    }
}

#[test]
fn a_fixed_heat_scale_is_used_as_given() {
    let s = Setup::new();
    let auto = s.frame(Method::Mft, FrameView::Nodes, 8, None);
    let fixed = s.frame(Method::Mft, FrameView::Nodes, 8, Some(1e6));
    assert_eq!(fixed.range, Some((0.0, 1e6)));
    assert_ne!(auto.rgba, fixed.rgba);
    // With a scale far above every count, everything is cold.
    assert!(fixed.rgba.iter().all(|c| c[2] >= c[0]));
}

#[test]
fn depth_and_normal_views_do_not_depend_on_the_method() {
    let s = Setup::new();
    for view in [FrameView::Depth, FrameView::Normals] {
        let mono = s.frame(Method::Mono, view, 8, None);
        for method in METHODS {
            let f = s.frame(method, view, 8, None);
            assert_eq!(f.rgba, mono.rgba, "{method} {view}");
            assert_eq!(f.range, mono.range, "{method} {view}");
        }
    }
    let depth = s.frame(Method::Mono, FrameView::Depth, 8, None);
    let (near, far) = depth.range.unwrap();
    assert!(near > 0.0 && near < far, "{near} {far}");
}

#[test]
fn ray_orders_change_no_pixel_and_heat_maps_ignore_the_order() {
    let s = Setup::new();
    let tracer = Tracer::new(&s.structures, TraceOptions::default()).unwrap();
    let cam = s.scene.default_view().unwrap().camera;
    let mut frames = Vec::new();
    for order in RayOrder::ALL {
        for view in [FrameView::Shaded, FrameView::Nodes] {
            let settings = RenderSettings { width: 37, height: 21, tile: 8, order, view, ..Default::default() };
            frames.push((order, view, render(&s.scene, &tracer, &cam, s.scene.lights[0], &settings)));
        }
    }
    for (order, view, f) in &frames {
        let base = frames.iter().find(|(o, v, _)| *o == RayOrder::Scanline && v == view).unwrap();
        assert_eq!(f.rgba, base.2.rgba, "{order} {view}");
    }
}
