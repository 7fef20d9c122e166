//! `raylab-bench info`: what a scene holds and what its kd-tree looks like.

use clap::Args;
use serde_json::json;

use crate::args::{KdArgs, SceneArgs, in_range};
use crate::prepare::{build_tree, load_scene};

/// Prints a scene's triangles, bounds, materials, lights, views and kd-tree statistics.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Threads for the kd-tree build.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(a: &InfoArgs) -> Result<(), String> {
    let (scene, load_s) = load_scene(&a.scene.source())?;
    let params = a.kd.params()?;
    let tree = build_tree(&scene, &params, a.threads as usize)?;
    let st = tree.stats();
    let b = scene.bounds();
    if a.json {
        let v = json!({
            "scene": a.scene.scene,
            "triangles": scene.triangle_count(),
            "dropped": { "bad_index": scene.dropped.bad_index, "non_finite": scene.dropped.non_finite,
                         "degenerate": scene.dropped.degenerate },
            "bounds": { "min": b.min.to_array(), "max": b.max.to_array() },
            "materials": scene.materials.iter().map(|m| &m.name).collect::<Vec<_>>(),
            "lights": scene.lights.len(),
            "views": scene.views.iter().map(|v| &v.name).collect::<Vec<_>>(),
            "load_seconds": load_s,
            "kd_params": params,
            "kd_build_threads": a.threads,
            "kdtree": st,
        });
        println!("{v}");
        return Ok(());
    }
    println!("scene            {}", a.scene.scene);
    println!("triangles        {} ({} dropped: {:?})", scene.triangle_count(), scene.dropped.total(), scene.dropped);
    println!("vertices         {}", scene.positions.len());
    println!("bounds           {:?} - {:?}, diagonal {:.4}", b.min.to_array(), b.max.to_array(), b.diagonal());
    let names: Vec<_> = scene.materials.iter().map(|m| format!("{} ({:?})", m.name, m.kind)).collect();
    println!("materials        {}: {}", names.len(), names.join(", "));
    println!("lights           {}", scene.lights.len());
    let views: Vec<_> = scene.views.iter().map(|v| v.name.as_str()).collect();
    println!("views            {}", if views.is_empty() { "none".into() } else { views.join(", ") });
    println!("load             {load_s:.3} s");
    println!(
        "kd params        c_trav {} c_isect {} empty_bonus {} max_depth {}",
        params.c_trav,
        params.c_isect,
        params.empty_bonus,
        params.depth_for(scene.triangle_count())
    );
    println!("kd build         {:.3} s on {} thread(s)", st.build_seconds, a.threads);
    println!("kd nodes         {} ({} inner, {} leaves, {} empty)", st.nodes, st.inner, st.leaves, st.empty_leaves);
    println!(
        "kd leaves        {:.2} triangles per non-empty leaf (max {}), {} references",
        st.avg_tris_per_leaf, st.max_tris_per_leaf, st.tri_refs
    );
    println!("kd depth         {}", st.max_depth);
    println!("kd bytes         {} ({:.2} MiB)", st.bytes, st.bytes as f64 / (1 << 20) as f64);
    println!("kd SAH cost      {:.3}", st.sah_cost);
    Ok(())
}
