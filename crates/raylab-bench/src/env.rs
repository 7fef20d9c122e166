//! The environment a measurement ran in, printed with every benchmark result.

use serde::Serialize;

/// Machine, build and code version.
#[derive(Clone, Debug, Serialize)]
pub struct Environment {
    /// `git describe` of the working tree (with `-dirty` when it has changes), or `unknown`.
    pub commit: String,
    /// The compiler that built this binary.
    pub rustc: &'static str,
    /// CPU model name.
    pub cpu: String,
    /// Logical CPUs.
    pub cpus: usize,
    /// SIMD extensions detected at run time.
    pub simd: Vec<&'static str>,
}

impl Environment {
    /// Gathers the environment.
    pub fn detect() -> Self {
        let commit = std::process::Command::new("git")
            .args(["describe", "--always", "--dirty", "--abbrev=12"])
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok())
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|| "unknown".into());
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| s.lines().find(|l| l.starts_with("model name")).map(|l| l.to_string()))
            .and_then(|l| l.split(':').nth(1).map(|s| s.trim().to_string()))
            .unwrap_or_else(|| std::env::consts::ARCH.into());
        Self {
            commit,
            rustc: env!("RAYLAB_RUSTC_VERSION"),
            cpu,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            simd: simd_features(),
        }
    }

    /// One line for reports.
    pub fn line(&self) -> String {
        format!(
            "commit {}, {}, CPU {} ({} logical CPUs, SIMD: {})",
            self.commit,
            self.rustc,
            self.cpu,
            self.cpus,
            if self.simd.is_empty() { "none".to_string() } else { self.simd.join(" ") }
        )
    }
}

#[cfg(target_arch = "x86_64")]
fn simd_features() -> Vec<&'static str> {
    let mut v = Vec::new();
    if is_x86_feature_detected!("sse4.1") {
        v.push("sse4.1");
    }
    if is_x86_feature_detected!("avx2") {
        v.push("avx2");
    }
    if is_x86_feature_detected!("fma") {
        v.push("fma");
    }
    if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") {
        v.push("avx512f/vl");
    }
    v
}

#[cfg(not(target_arch = "x86_64"))]
fn simd_features() -> Vec<&'static str> {
    Vec::new()
}
