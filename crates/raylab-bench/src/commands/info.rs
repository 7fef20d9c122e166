//! `raylab-bench info`: what a scene holds and what its kd-tree looks like.

use clap::Args;
use serde_json::json;

use crate::args::{KdArgs, SceneArgs, in_range};
use crate::prepare::{build_tree, load_scene_verbose};

/// Prints a scene's triangles, bounds, materials, textures, lights, views, the loader's warnings and kd-tree
/// statistics.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    kd: KdArgs,
    /// Build the kd-tree that this method walks (its cost model: packet and frustum methods have their own).
    #[arg(long, default_value = "mono")]
    method: raylab_core::method::Method,
    /// Threads for the kd-tree build.
    #[arg(long, default_value_t = 1, value_parser = in_range(1, 1024))]
    threads: u64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(a: &InfoArgs) -> Result<(), String> {
    let (raylab_scene::Loaded { scene, warnings }, load_s) = load_scene_verbose(&a.scene.source())?;
    let params = *a.kd.structure_params()?.kd_for(a.method);
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
            "materials": scene.materials,
            "textures": scene.textures.iter().map(|t| json!({ "name": t.name, "width": t.width, "height": t.height }))
                .collect::<Vec<_>>(),
            "lights": scene.lights,
            "views": scene.views.iter().map(|v| &v.name).collect::<Vec<_>>(),
            "warnings": warnings,
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
    println!("materials        {}", scene.materials.len());
    for m in &scene.materials {
        let tex = |t: Option<u32>| t.and_then(|i| scene.textures.get(i as usize)).map(|t| t.name.clone());
        let mut line = format!("  {} ({:?}, base {:?}", m.name, m.kind, m.base_color.to_array());
        if let Some(t) = tex(m.diffuse_texture) {
            line += &format!(", diffuse map {t}");
        }
        if let Some(t) = tex(m.normal_texture) {
            line += &format!(", normal map {t}");
        }
        println!("{line})");
    }
    println!("textures         {}", scene.textures.len());
    for t in &scene.textures {
        println!("  {} ({}x{})", t.name, t.width, t.height);
    }
    println!("lights           {}", scene.lights.len());
    for l in &scene.lights {
        println!("  at {:?}, colour {:?}, radius {}", l.position.to_array(), l.color.to_array(), l.radius);
    }
    let views: Vec<_> = scene.views.iter().map(|v| v.name.as_str()).collect();
    println!("views            {}", if views.is_empty() { "none".into() } else { views.join(", ") });
    println!("warnings         {}", warnings.len());
    for w in &warnings {
        println!("  {w}");
    }
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
