//! Headless OpenGL contexts.
