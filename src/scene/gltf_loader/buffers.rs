//! Buffers: each buffer's bytes, from the `.glb` binary chunk, a data URI
//! or a file, checked against its declared length, and the bounds-checked
//! bytes of a buffer view.

use std::path::Path;

use super::uri::{UriSource, display_uri, resolve_uri};

/// Loads every buffer of the document, in order.
// Not gltf::import_buffers (gltf 1.4.1): buffer::Data::from_source_and_blob
// zero-pads each buffer to a multiple of four bytes before the byteLength
// check, so a view overrunning the data by up to 3 bytes reads zeros
// instead of failing; it `take`s the BIN chunk, so a second buffer naming
// it fails with `MissingBlob`; and it resolves URIs with the importer's
// scheme parser (see `uri`).
pub(super) fn load_buffers(
    doc: &gltf::Document,
    base: Option<&Path>,
    bin: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let (data, what) = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let Some(bin) = bin else {
                    return Err(format!(
                        "buffer {i} refers to the .glb binary chunk, which is missing"
                    ));
                };
                (bin.to_vec(), "the .glb binary chunk".to_string())
            }
            gltf::buffer::Source::Uri(uri) => {
                match resolve_uri(uri, base).map_err(|e| format!("buffer {i}: {e}"))? {
                    UriSource::Bytes(b) => (b, display_uri(uri)),
                    UriSource::File(file) => match std::fs::read(&file) {
                        Ok(b) => (b, display_uri(uri)),
                        Err(e) => {
                            return Err(format!(
                                "missing buffer file {} (buffer {i}): {e}",
                                display_uri(uri)
                            ));
                        }
                    },
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} ({what}) has {} bytes, fewer than its declared byteLength {} (truncated?)",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a buffer view.
pub(super) fn view_bytes<'b>(
    view: &gltf::buffer::View,
    buffers: &'b [Vec<u8>],
) -> Result<&'b [u8], String> {
    let buffer = view.buffer().index();
    let data = buffers
        .get(buffer)
        .ok_or_else(|| format!("buffer view {} names missing buffer {buffer}", view.index()))?;
    let start = view.offset();
    let end = start.saturating_add(view.length());
    data.get(start..end).ok_or_else(|| {
        format!(
            "buffer view {} (bytes {start}..{end}) lies outside buffer {buffer} ({} bytes)",
            view.index(),
            data.len()
        )
    })
}
