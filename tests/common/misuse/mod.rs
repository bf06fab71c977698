//! The C API's misuse fuzzer: random call sequences over a real context,
//! with the host's GL state compared around every call. One sequence in
//! three drives the Rust API (`MsaaRetrofit`) the same way, leaving out
//! what its types cannot express ([`Api::Rust`]).
//!
//! A sequence is drawn from a `u64` seed (the kit's `Rng`): a host
//! G-buffer (one to three colour attachments, depth with or without
//! stencil), then calls in any order: `dmsaa_retrofit_new` with options in
//! and out of range, framebuffer ids that are the host's, 0, no
//! framebuffer, or one without depth, and loaders that return null for one
//! function; resolves with perspective, orthographic, NaN or null
//! projections; the second layer's calls in and out of order with good and
//! bad outputs; `set_options`, `refresh`, the getters, null handles and
//! `dmsaa_destroy`; between them the host re-allocates one attachment at
//! another size, deletes one, puts its G-buffer back, draws, and leaves
//! random GL state behind (per-buffer blend enables and colour masks,
//! stencil functions with references 0..255 while a framebuffer without
//! stencil is bound, scissor, viewport, bindings, ...).
//!
//! Around every call: the GL state snapshot (`gl_state`, indexed state and
//! the stencil references included) is unchanged, `glGetError` is clean,
//! no call panics, a failure has a one-line message, a failed
//! `dmsaa_retrofit_new` leaves `*out` null and nothing allocated. After a
//! failed call on a handle, and at the end, the host puts its G-buffer
//! back and `dmsaa_refresh` must succeed and the next resolve give the
//! right frame: every attachment and the depth of a uniform draw come back
//! as the host's own clear of them.
//!
//! [`run_sequence`] runs one and returns its failures; [`shrink`] drops
//! calls while a failure stays; the slow tier's test runs sequences in
//! child processes (a crash or a hang is that sequence's) and prints each
//! failure's shrunk sequence with the command that replays it.

mod calls;
mod host;
mod rust_api;
mod sequence;

use deferred_msaa_capi as c;
use deferred_msaa_lab::context::HeadlessContext;

use calls::*;
// The fast and the slow tier each name some of these.
#[allow(unused_imports)]
pub use calls::{last_message, take_call_count, take_stats};
use host::*;
pub use sequence::*;

/// Run `sequence` on `context` (current on this thread); its failures,
/// empty when every check held.
pub fn run_sequence(context: &HeadlessContext, sequence: &Sequence) -> Vec<String> {
    let gl = context.gl();
    reset(gl);
    let live = c::dmsaa_live_objects();
    let host = Host::new(gl, sequence.colors, sequence.stencil);
    let mut run = Run {
        gl,
        context,
        host,
        slots: [None, None],
        retrofits: [None, None],
        api: sequence.api,
        in_rust_call: false,
        failures: Vec::new(),
    };
    let end = sequence.ops.len();
    for (index, op) in sequence.ops.iter().enumerate() {
        run.step(index, op);
    }
    for k in 0..2 {
        if run.slots[k].is_some() || run.retrofits[k].is_some() {
            run.step(end, &Op::Recover(Which::Slot(k)));
            run.step(end, &Op::Destroy(Which::Slot(k)));
        }
    }
    if c::dmsaa_live_objects() != live {
        run.failures.push(format!(
            "{} GL objects of the library's left after every handle was destroyed",
            c::dmsaa_live_objects() - live
        ));
    }
    let Run { host, failures, .. } = run;
    host.destroy(gl);
    reset(gl);
    failures
}

/// The smallest sequence found that still fails (dropping one call at a
/// time while a failure stays): the indices of the calls kept, and its
/// failures.
pub fn shrink(context: &HeadlessContext, sequence: &Sequence) -> (Vec<usize>, Vec<String>) {
    let mut keep: Vec<usize> = (0..sequence.ops.len()).collect();
    let mut failures = run_sequence(context, sequence);
    let mut i = keep.len();
    while i > 0 {
        i -= 1;
        let mut fewer = keep.clone();
        fewer.remove(i);
        let f = run_sequence(context, &sequence.only(&fewer));
        if !f.is_empty() {
            keep = fewer;
            failures = f;
        }
    }
    (keep, failures)
}

/// `keep` as the replay variable's value: `SEED:i,j,k`.
pub fn replay_value(seed: u64, keep: &[usize]) -> String {
    let list: Vec<String> = keep.iter().map(usize::to_string).collect();
    format!("{seed}:{}", list.join(","))
}
