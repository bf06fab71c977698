//! URIs, as buffers and images name them: data URIs (base64 or
//! percent-encoded) decoded to bytes, `file:` and relative references
//! resolved to paths under the file's folder, other schemes refused.

use std::path::{Path, PathBuf};

/// Where a URI's bytes come from.
pub(super) enum UriSource {
    /// The bytes themselves, decoded from a data URI.
    Bytes(Vec<u8>),
    /// A file to read.
    File(PathBuf),
}

/// Resolves a URI against `base`, the folder of the file (`None` when
/// loading from memory: then only data URIs are accepted).
// Not the crate's importer (gltf 1.4.1, import.rs's private Scheme, behind
// gltf::buffer::Data::from_source and gltf::image::Data::from_source):
// it calls `urlencoding::decode(uri).unwrap()`, a panic on %-escapes that
// are not UTF-8; it leaves `file:` paths undecoded; it calls every other URI
// holding a ':' (a drive letter, a ':' in a file name) an unsupported scheme;
// and it base64-decodes a data URI without `;base64,`, so percent-encoded
// data URIs fail.
pub(super) fn resolve_uri(uri: &str, base: Option<&Path>) -> Result<UriSource, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(',') else {
            return Err("malformed data URI (no ',')".into());
        };
        let is_base64 = rest
            .split_once(',')
            .is_some_and(|(meta, _)| meta.ends_with(";base64"));
        return if is_base64 {
            decode_base64(payload).map(UriSource::Bytes)
        } else {
            Ok(UriSource::Bytes(percent_decode(payload)))
        };
    }
    let Some(base) = base else {
        return Err(format!(
            "external file {} cannot be read when loading from memory",
            display_uri(uri)
        ));
    };
    if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        let decoded = percent_decode(rest);
        return Ok(UriSource::File(PathBuf::from(
            String::from_utf8_lossy(&decoded).into_owned(),
        )));
    }
    // A scheme is letters/digits/+-. before the first ':' (and no '/' first).
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1 // not a Windows drive letter
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if let Some(scheme) = scheme {
        return Err(format!("unsupported URI scheme '{scheme}:'"));
    }
    let decoded = percent_decode(uri);
    Ok(UriSource::File(
        base.join(String::from_utf8_lossy(&decoded).into_owned()),
    ))
}

/// A URI as messages name it: data URIs (often megabytes) by their kind only.
pub(super) fn display_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        "embedded data URI".to_string()
    } else {
        format!("'{uri}'")
    }
}

/// `%XX` escapes decoded; a `%` without two hex digits stays as it is.
fn percent_decode(s: &str) -> Vec<u8> {
    percent_encoding::percent_decode_str(s).collect()
}

/// Standard or URL-safe base64, padding optional, whitespace ignored, and
/// nothing after the first `=` (lenient, as glTF writers in the wild are).
// The importer of gltf 1.4.1 decodes with base64 0.13's `base64::decode`
// (the standard alphabet): it refuses URL-safe characters, whitespace (line
// breaks in wrapped payloads), non-zero trailing bits and text after the
// padding.
fn decode_base64(s: &str) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const LENIENT: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new()
            .with_decode_padding_mode(DecodePaddingMode::RequireNone)
            .with_decode_allow_trailing_bits(true),
    );
    let payload = s.split('=').next().unwrap_or("");
    let standard: String = payload
        .chars()
        .filter(|c| !c.is_ascii_whitespace())
        .map(|c| match c {
            '-' => '+',
            '_' => '/',
            c => c,
        })
        .collect();
    LENIENT.decode(standard.as_bytes()).map_err(|e| match e {
        base64::DecodeError::InvalidByte(at, byte) => format!(
            "invalid base64 data: {:?} at character {at} of the payload",
            char::from(byte)
        ),
        other => format!("invalid base64 data: {other}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(uri: &str, base: Option<&Path>) -> Result<PathBuf, String> {
        match resolve_uri(uri, base)? {
            UriSource::File(path) => Ok(path),
            UriSource::Bytes(_) => Err(format!("{uri}: bytes, expected a file")),
        }
    }

    #[test]
    fn external_files_from_memory_are_named_once_quoted() {
        let Err(msg) = file("quad.bin", None) else {
            panic!("an external file from memory must be refused");
        };
        assert!(msg.contains("external file 'quad.bin' cannot"), "{msg}");
    }

    #[test]
    fn file_uris_and_relative_paths_are_percent_decoded() {
        let base = Path::new("models");
        assert_eq!(file("a%20b.bin", Some(base)), Ok(base.join("a b.bin")));
        assert_eq!(
            file("file:///tmp/a%20b.bin", Some(base)),
            Ok(PathBuf::from("/tmp/a b.bin"))
        );
        assert_eq!(file("C:/x.bin", Some(base)), Ok(base.join("C:/x.bin")));
    }

    #[test]
    fn data_uris_decode_leniently() {
        for uri in [
            "data:,%41%42",
            "data:;base64,QUI",
            "data:;base64,Q U\nI=junk",
        ] {
            match resolve_uri(uri, None) {
                Ok(UriSource::Bytes(b)) => assert_eq!(b, b"AB", "{uri}"),
                Ok(UriSource::File(p)) => panic!("{uri}: a file {p:?}"),
                Err(e) => panic!("{uri}: {e}"),
            }
        }
    }
}
