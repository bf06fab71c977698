//! What the library keeps per GL context, and what each watched call does:
//! find the G-buffer, bind the retrofit's framebuffer in its place, resolve
//! when the program leaves it.
//!
//! The calls come in through [`handlers`]; the state they work on is
//! [`context`]'s, and its parts are [`camera_block`] (the camera read
//! from a uniform block, named or found by its values), [`clears`] (a clear through
//! another framebuffer sharing the G-buffer's attachments, replayed), [`content`] (the first resolve's G-buffer
//! read back, a warning where it shows nothing), [`gbuffer`] (finding the G-buffer),
//! [`framebuffers`] (the binds and attachments followed), [`retrofit`] (the
//! C API's retrofit made, bound, resolved, its second layer), [`forward`]
//! (what is drawn forward after the lighting, into the forward target),
//! [`lighting_calls`] (the calls between the lighting's draws kept for its
//! replay), [`run`]
//! (the settings and messages of the whole run) and [`learn`] (`--learn`'s
//! profile).

mod camera_block;
mod clears;
mod content;
mod context;
mod forward;
mod framebuffers;
mod gbuffer;
pub(crate) mod handlers;
mod learn;
mod lighting_calls;
mod retrofit;
mod run;
