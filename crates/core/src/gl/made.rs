//! The construction guard: what a constructor made before it failed is
//! destroyed, explicitly, with the context it was made in.
//!
//! GL objects are never freed on drop (see the module docs of [`gl`](super)),
//! so a guard cannot rely on `Drop` either. [`Made::build`] instead runs the
//! constructor as a closure: every object passed through [`Made::keep`] is
//! recorded by handle, and when the closure returns `Err` those handles are
//! deleted, newest first, through the same counters the objects' own
//! `destroy` uses, so [`live_objects`](super::live_objects) still proves
//! that nothing leaks. On `Ok` the records are dropped and the objects live
//! on in what the closure returned.

use super::counters::{self, Kind};
use super::{
    Buffer, Framebuffer, GpuTimer, Program, SamplesPassedQuery, Texture2d, Texture2dArray,
    Texture2dMultisample, VertexArray,
};
use glow::HasContext;

/// One GL object, by handle, as the guard records it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Handle(Raw);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Raw {
    Texture(glow::Texture),
    Framebuffer(glow::Framebuffer),
    Program(glow::Program),
    Buffer(glow::Buffer),
    VertexArray(glow::VertexArray),
    Query(glow::Query),
}

impl Handle {
    fn delete(self, gl: &glow::Context) {
        unsafe {
            match self.0 {
                Raw::Texture(t) => {
                    gl.delete_texture(t);
                    counters::destroyed(Kind::Texture);
                }
                Raw::Framebuffer(f) => {
                    gl.delete_framebuffer(f);
                    counters::destroyed(Kind::Framebuffer);
                }
                Raw::Program(p) => {
                    gl.delete_program(p);
                    counters::destroyed(Kind::Program);
                }
                Raw::Buffer(b) => {
                    gl.delete_buffer(b);
                    counters::destroyed(Kind::Buffer);
                }
                Raw::VertexArray(v) => {
                    gl.delete_vertex_array(v);
                    counters::destroyed(Kind::VertexArray);
                }
                Raw::Query(q) => {
                    gl.delete_query(q);
                    counters::destroyed(Kind::Query);
                }
            }
        }
    }
}

/// Something that owns GL objects and can list them for [`Made`].
///
/// A composite implements it by listing its parts; the handles must be
/// exactly what its own `destroy` frees.
pub trait GlObject {
    /// Push the handles of every GL object this value owns.
    fn handles(&self, out: &mut Vec<Handle>);
}

macro_rules! gl_object {
    ($($ty:ty => $variant:ident),* $(,)?) => {
        $(impl GlObject for $ty {
            fn handles(&self, out: &mut Vec<Handle>) {
                out.push(Handle(Raw::$variant(self.raw)));
            }
        })*
    };
}

gl_object! {
    Texture2d => Texture,
    Texture2dMultisample => Texture,
    Texture2dArray => Texture,
    Framebuffer => Framebuffer,
    Program => Program,
    Buffer => Buffer,
    VertexArray => VertexArray,
    SamplesPassedQuery => Query,
}

impl GlObject for GpuTimer {
    fn handles(&self, out: &mut Vec<Handle>) {
        if let Some(q) = self.query {
            out.push(Handle(Raw::Query(q)));
        }
    }
}

impl<T: GlObject> GlObject for Option<T> {
    fn handles(&self, out: &mut Vec<Handle>) {
        if let Some(t) = self {
            t.handles(out);
        }
    }
}

impl<T: GlObject> GlObject for Vec<T> {
    fn handles(&self, out: &mut Vec<Handle>) {
        for t in self {
            t.handles(out);
        }
    }
}

/// Free every GL object `object` owns, as its [`GlObject::handles`] lists
/// them, newest first (as a failed [`Made::build`] frees them). A
/// composite's `destroy` is this one call, so what it frees is what it
/// lists and the two cannot drift apart.
pub fn destroy_object(gl: &glow::Context, object: impl GlObject) {
    let mut handles = Vec::new();
    object.handles(&mut handles);
    for handle in handles.into_iter().rev() {
        handle.delete(gl);
    }
}

/// The objects a constructor has made so far; see [`Made::build`].
///
/// ```no_run
/// # fn f(gl: &glow::Context) -> deferred_msaa::Result<()> {
/// use deferred_msaa::gl::{Attachment, Format, Framebuffer, Made, Texture2d, TextureRef};
/// let (texture, fbo) = Made::build(gl, |made| {
///     let texture = made.keep(Texture2d::new(gl, "colour", Format::Rgba8, 64, 64)?);
///     // If this fails, `texture` is deleted before the error is returned.
///     let fbo = made.keep(Framebuffer::new(
///         gl,
///         "colour",
///         &[(Attachment::Color(0), TextureRef::from(&texture))],
///         &[Some(0)],
///     )?);
///     Ok::<_, deferred_msaa::Error>((texture, fbo))
/// })?;
/// # fbo.destroy(gl); texture.destroy(gl); Ok(()) }
/// ```
#[derive(Debug, Default)]
pub struct Made {
    handles: Vec<Handle>,
}

impl Made {
    /// Run the constructor `f`; if it returns `Err`, or panics, destroy
    /// everything it passed through [`Made::keep`] (newest first) and
    /// return the error (or go on unwinding).
    ///
    /// Objects kept must not be destroyed inside `f` (they would be freed twice).
    pub fn build<T, E>(
        gl: &glow::Context,
        f: impl FnOnce(&mut Made) -> Result<T, E>,
    ) -> Result<T, E> {
        /// Frees what was kept when dropped unarmed: after an `Err` and
        /// while a panic unwinds.
        struct Undo<'a> {
            gl: &'a glow::Context,
            made: Made,
            succeeded: bool,
        }
        impl Drop for Undo<'_> {
            fn drop(&mut self) {
                if !self.succeeded {
                    for handle in std::mem::take(&mut self.made.handles).into_iter().rev() {
                        handle.delete(self.gl);
                    }
                }
            }
        }
        let mut undo = Undo {
            gl,
            made: Made::default(),
            succeeded: false,
        };
        let result = f(&mut undo.made);
        undo.succeeded = result.is_ok();
        result
    }

    /// Record `object` so that a failure later in the constructor frees it.
    pub fn keep<O: GlObject>(&mut self, object: O) -> O {
        object.handles(&mut self.handles);
        object
    }
}

/// A value owning GL objects that is destroyed ([`destroy_object`]) when
/// dropped, unless taken out with [`Owned::into_inner`]: for a step after
/// construction (compiling a made retrofit's programs, say) that may fail or
/// panic, so that neither way out leaks what was made.
pub struct Owned<'a, T: GlObject> {
    gl: &'a glow::Context,
    value: Option<T>,
}

impl<'a, T: GlObject> Owned<'a, T> {
    /// Own `value` until [`Owned::into_inner`].
    pub fn new(gl: &'a glow::Context, value: T) -> Self {
        Owned {
            gl,
            value: Some(value),
        }
    }

    /// The value, no longer destroyed on drop.
    pub fn into_inner(mut self) -> T {
        match self.value.take() {
            Some(value) => value,
            // `value` is `Some` from `new` until this call, which consumes
            // the guard.
            None => unreachable!("an Owned guard's value is taken once"),
        }
    }
}

impl<T: GlObject> std::ops::Deref for Owned<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        match &self.value {
            Some(value) => value,
            None => unreachable!("an Owned guard's value is taken once"),
        }
    }
}

impl<T: GlObject> std::ops::DerefMut for Owned<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        match &mut self.value {
            Some(value) => value,
            None => unreachable!("an Owned guard's value is taken once"),
        }
    }
}

impl<T: GlObject> Drop for Owned<'_, T> {
    fn drop(&mut self) {
        if let Some(value) = self.value.take() {
            destroy_object(self.gl, value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_and_vectors_list_their_parts() {
        let none: Option<Vec<Texture2d>> = None;
        let mut out = Vec::new();
        none.handles(&mut out);
        assert!(out.is_empty());
    }
}
