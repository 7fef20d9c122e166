//! Writing a command's report files: every command that takes `--markdown FILE` or `--json FILE` writes
//! them the same way, and an error names the flag and the file.

use std::path::Path;

use serde_json::{Value, json};

use crate::env::Environment;

/// The opening lines of every markdown report: the machine and build it ran on, and the exact command line
/// `cmd`, so that a table in docs/BENCHMARKS.md says how to make it again.
pub fn markdown_header(env: &Environment, cmd: &[String]) -> String {
    format!("Machine and build: {}.\nCommand: `{}`\n", env.line(), cmd.join(" "))
}

/// Writes `text` to the file `path` given with `flag` (such as `--markdown`).
pub fn write_text(flag: &str, path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("{flag}: cannot write {}: {e}", path.display()))
}

/// Prints the markdown report `md` and writes it to the `--markdown` file, if one was given.
pub fn print_markdown(md: &str, path: Option<&Path>) -> Result<(), String> {
    print!("{md}");
    path.map_or(Ok(()), |p| write_text("--markdown", p, md))
}

/// Writes the report `body` (a JSON object) to the `--json` file `path`, indented, with a final newline,
/// adding the machine and build (`environment`) and the exact command line (`command`), as every markdown
/// report opens with them ([`markdown_header`]).
pub fn write_json(path: &Path, env: &Environment, cmd: &[String], mut body: Value) -> Result<(), String> {
    if let Some(o) = body.as_object_mut() {
        o.insert("environment".into(), json!(env));
        o.insert("command".into(), json!(cmd));
    }
    write_text("--json", path, &format!("{body:#}\n"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The JSON file parses back to the report with the machine and the command added; a file that cannot be
    /// written names the flag and the path.
    #[test]
    fn writes_json_and_names_flag_and_file_on_error() {
        let dir = std::env::temp_dir().join(format!("raylab-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.json");
        let (env, cmd) = (Environment::detect(), vec!["raylab-bench".to_string(), "tables".to_string()]);
        write_json(&path, &env, &cmd, json!({ "fps": 12.5, "rows": [1, 2] })).unwrap();
        let back = std::fs::read_to_string(&path).unwrap();
        assert!(back.ends_with('\n'));
        let want = json!({ "fps": 12.5, "rows": [1, 2], "environment": env, "command": cmd });
        assert_eq!(serde_json::from_str::<Value>(&back).unwrap(), want);
        let missing = dir.join("no/such/dir/t.md");
        let err = write_text("--markdown", &missing, "x").unwrap_err();
        assert!(err.starts_with("--markdown: cannot write ") && err.contains("t.md"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
