//! The environment a measurement ran in, printed with every benchmark result.

use serde::Serialize;

/// Machine, build and code version.
#[derive(Clone, Debug, Serialize)]
pub struct Environment {
    /// `git describe` of the working tree (with `-dirty` when it has changes), or `unknown`.
    pub commit: String,
    /// The compiler that built this binary.
    pub rustc: &'static str,
    /// CPU model name, with the family and model numbers where the kernel reports them (virtual machines often
    /// name every generation alike, "AMD EPYC", and the numbers tell them apart).
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
            .and_then(|info| cpu_name(&info))
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

/// The first processor's model name from `/proc/cpuinfo` text, followed by its family and model numbers when
/// both are there.
fn cpu_name(info: &str) -> Option<String> {
    let field = |key: &str| {
        info.lines()
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == key))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let name = field("model name")?;
    Some(match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => format!("{name}, family {family} model {model}"),
        _ => name,
    })
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

#[cfg(test)]
mod tests {
    use super::cpu_name;

    #[test]
    fn cpu_name_carries_family_and_model_when_known() {
        let info =
            "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 26\nmodel\t\t: 2\nmodel name\t: AMD EPYC\n";
        assert_eq!(cpu_name(info).as_deref(), Some("AMD EPYC, family 26 model 2"));
        assert_eq!(cpu_name("model name\t: Some CPU\n").as_deref(), Some("Some CPU"));
        assert_eq!(cpu_name("flags\t: sse2\n"), None);
    }
}
