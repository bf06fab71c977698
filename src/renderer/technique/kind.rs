//! What is known of a technique before anything is built ([`Kind`]), which
//! the options, the plan, the bench and the command line ask.

use super::contract::Technique;
use crate::Result;
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::AaMode;

/// What is known of a technique before anything is built: its method names
/// and how they parse, and the facts the options, the plan, the bench and
/// the command line ask of it. The defaults are `none`'s.
pub(crate) trait Kind: Sync {
    /// The method names it renders, as `--method` and bench entries spell them.
    fn methods(&self) -> &'static [&'static str];

    /// The technique's name: its one method's (`resolve` for the four
    /// resolve methods). Methods of one technique can share a renderer.
    fn name(&self) -> &'static str {
        self.methods()[0]
    }

    /// Whether it renders `aa`.
    fn renders(&self, aa: &AaMode) -> bool;

    /// The method name of `aa`, which it renders.
    fn method_name(&self, _aa: &AaMode) -> &'static str {
        self.name()
    }

    /// The mode for `method` (one of [`Kind::methods`]) with `options`, the
    /// parts of a method spec after its colons; errors are one line that
    /// names `spec`.
    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode>;

    /// The options [`Kind::parse`] takes, for error messages; `None`: none.
    fn options_help(&self) -> Option<&'static str> {
        None
    }

    /// Whether the G-buffer pass draws into the retrofit's multisampled twins.
    fn draws_into_twins(&self) -> bool {
        false
    }

    /// Whether it renders more than one sample per pixel, so that
    /// [`RenderOptions::samples`] applies.
    fn takes_samples(&self) -> bool {
        self.draws_into_twins()
    }

    /// Whether lighting lights samples of the twins rather than resolved pixels.
    fn lights_per_sample(&self) -> bool {
        false
    }

    /// Whether its G-buffer pass does more than `none`'s (the bench then
    /// counts its G-buffer time beyond `none`'s as anti-aliasing time).
    fn adds_geometry(&self) -> bool {
        false
    }

    /// Whether its lighting does more than `none`'s per-pixel pass (the
    /// bench then counts its lighting time beyond `none`'s likewise).
    fn adds_lighting(&self) -> bool {
        self.lights_per_sample()
    }

    /// Whether the G-buffer pass fills the G-buffer's attachments.
    fn fills_gbuffer(&self) -> bool {
        true
    }

    /// The plan's lighting passes for `aa`, in frame order.
    fn lighting_passes(&self, _aa: &AaMode) -> Vec<Pass> {
        vec![Pass::Lighting]
    }

    /// The plan's passes after the tonemap and before FXAA.
    fn post_passes(&self) -> Vec<Pass> {
        Vec::new()
    }

    /// The plan's name for its G-buffer program.
    fn geometry_program(&self) -> &'static str {
        "geometry"
    }

    /// The plan's names of the programs it compiles beside the G-buffer,
    /// resolve and lighting programs, in frame order.
    fn own_programs(&self) -> &'static [&'static str] {
        &[]
    }

    /// How many frames `aa` must render, from a fresh state, before its
    /// image is what a still camera settles on (a temporal method's
    /// history); the bench renders them before it measures a still frame.
    fn warmup_frames(&self, _aa: &AaMode) -> u32 {
        0
    }

    /// The technique, in an empty state (nothing is built before it is
    /// first used).
    fn build(&self) -> Box<dyn Technique>;
}

/// The error for options given to a method that takes none.
pub(crate) fn no_options(method: &str, options: &[&str], spec: &str) -> Result<()> {
    match options.first() {
        None => Ok(()),
        Some(o) => Err(crate::Error::invalid(format!(
            "method `{spec}`: `{method}` takes no options (got `:{o}`)"
        ))),
    }
}
