//! Where a glTF file's bytes come from: the GLB binary chunk, base64 data URIs, or files next to the model
//! (confined to its folder), and the checks that let accessors be read without any out-of-bounds access.

use std::path::Path;

use base64::Engine as _;
use gltf::accessor::{DataType, Dimensions};

/// Decodes a `data:` URI with base64 content.
pub fn data_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
    let rest = uri.strip_prefix("data:")?;
    let Some((_, payload)) = rest.split_once(";base64,") else {
        return Some(Err("a data URI without base64 content".into()));
    };
    Some(
        base64::engine::general_purpose::STANDARD
            .decode(payload.trim())
            .map_err(|e| format!("bad base64 data URI: {e}")),
    )
}

/// The bytes a buffer or image URI names: a data URI, or a file resolved inside `root`.
pub fn uri_bytes(uri: &str, root: &Path) -> Result<Vec<u8>, String> {
    if let Some(data) = data_uri(uri) {
        return data;
    }
    let decoded = percent_decode(uri);
    let file = crate::paths::resolve(root, root, &decoded)?;
    std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// `%20`-style escapes in a URI path.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let escaped =
            (b[i] == b'%').then(|| s.get(i + 1..i + 3)).flatten().and_then(|h| u8::from_str_radix(h, 16).ok());
        match escaped {
            Some(v) => {
                out.push(v);
                i += 3;
            }
            None => {
                out.push(b[i]);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Checks that `accessor` can be read as `want` types from `buffers` without reading past any end: it has a
/// buffer view (sparse accessors are not read), the right component types and shape, a stride no smaller than
/// an element, and all its elements inside the view and the view inside its buffer.
pub fn check_accessor(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    types: &[DataType],
    dims: Dimensions,
) -> Result<(), String> {
    let what = format!("accessor {}", accessor.index());
    if accessor.sparse().is_some() {
        return Err(format!("{what} is sparse, which raylab does not read"));
    }
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dims {
        return Err(format!(
            "{what} has type {:?} {:?}, expected {dims:?} of {types:?}",
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    let view = accessor.view().ok_or_else(|| format!("{what} has no buffer view"))?;
    let data = buffers.get(view.buffer().index()).ok_or_else(|| format!("{what}: missing buffer"))?;
    let view_end = view.offset().checked_add(view.length()).ok_or_else(|| format!("{what}: view overflows"))?;
    if view_end > data.len() {
        return Err(format!(
            "{what}: buffer view {} ends at byte {view_end}, past its buffer's {} bytes",
            view.index(),
            data.len()
        ));
    }
    let elem = accessor.size();
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(format!("{what}: stride {stride} is smaller than an element ({elem} bytes)"));
    }
    let count = accessor.count();
    // glTF requires at least one element (and gltf 1.4.1 computes `count - 1` unchecked).
    if count == 0 {
        return Err(format!("{what} has no elements"));
    }
    {
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(accessor.offset()))
            .and_then(|x| x.checked_add(elem))
            .ok_or_else(|| format!("{what}: size overflows"))?;
        if end > view.length() {
            return Err(format!("{what}: {count} elements need {end} bytes, its view has {}", view.length()));
        }
    }
    Ok(())
}
