//! Scenes: glTF loading and built-ins.
