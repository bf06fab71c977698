//! Images: a texture's encoded bytes, from a buffer view or a URI, decoded
//! to sRGB RGBA8 texture data.

use std::path::Path;

use super::super::TextureData;
use super::buffers::view_bytes;
use super::uri::{UriSource, display_uri, resolve_uri};

/// Reads and decodes image `index` of `document`.
// Not gltf::image::Data::from_source (gltf 1.4.1): it indexes
// `buffer_data[view.buffer().index()][offset..offset + length]` unchecked,
// a panic for a view past its buffer's end; it refuses every URI, data URIs
// included, when there is no base folder (loading from memory); and without
// the crate's `guess_mime_type` feature it picks the decoder from the
// mimeType or the file extension alone, where this reads the bytes' magic.
// Nor gltf::Image::source: it unwraps the mimeType of a buffer-view image
// and the uri of any other, neither of which validation requires; the
// image's JSON is read here instead.
pub(super) fn decode_image(
    document: &gltf::Document,
    index: usize,
    buffers: &[Vec<u8>],
    base: Option<&Path>,
) -> Result<TextureData, String> {
    let json = document
        .as_json()
        .images
        .get(index)
        .ok_or_else(|| format!("no image {index} in the file"))?;
    let (bytes, what) = match (&json.buffer_view, &json.uri) {
        (Some(view), _) => {
            let view = document
                .views()
                .nth(view.value())
                .ok_or_else(|| format!("it names missing buffer view {}", view.value()))?;
            (
                view_bytes(&view, buffers)?.to_vec(),
                format!("buffer view {}", view.index()),
            )
        }
        (None, Some(uri)) => match resolve_uri(uri, base)? {
            UriSource::Bytes(b) => (b, display_uri(uri)),
            UriSource::File(file) => match std::fs::read(&file) {
                Ok(b) => (b, display_uri(uri)),
                Err(e) => return Err(format!("missing image file {}: {e}", display_uri(uri))),
            },
        },
        (None, None) => return Err("it has neither a bufferView nor a uri".into()),
    };
    let decoded = image::load_from_memory(&bytes).map_err(|e| {
        let jpeg = bytes.starts_with(&[0xFF, 0xD8, 0xFF]);
        if jpeg && matches!(e, image::ImageError::Unsupported(_)) {
            format!("{what} is a JPEG and this build cannot decode JPEG (enable the image crate's `jpeg` feature)")
        } else {
            format!("cannot decode {what}: {e}")
        }
    })?;
    let rgba = decoded.to_rgba8();
    Ok(TextureData {
        width: rgba.width(),
        height: rgba.height(),
        rgba8: rgba.into_raw(),
        srgb: true,
    })
}
