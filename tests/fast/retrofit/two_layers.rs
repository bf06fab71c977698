//! The second layer through the public API: calls out of order, hosts
//! without draw buffers to spare or with wide G-buffers, the mix of the two
//! lit layers, what is put back of the first layer, and the selection.

use super::*;

/// The second layer's calls in the wrong order, or without two layers, are
/// one-line errors that leave the retrofit working; with one layer
/// `begin_second_layer` does nothing and says so.
#[test]
fn second_layer_calls_out_of_order_are_errors() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let output = Some(host.fbo.raw());
    assert!(!msaa.begin_second_layer(gl, output).unwrap());
    assert!(msaa.second_layer_coverage().is_none());
    assert_eq!(msaa.second_layer_bytes(), 0);
    let one_line = |e: Error| {
        let text = e.to_string();
        assert_eq!(text.lines().count(), 1, "{text}");
        text
    };
    let text = one_line(msaa.finish_second_layer(gl, output).unwrap_err());
    assert!(text.contains("two layers"), "{text}");

    let two = RetrofitOptions {
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        layer_mix: LayerMix::Tonemapped, // an RGBA16F lit output: its tonemap declared
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        ..options
    };
    msaa.set_options(gl, &two).unwrap();
    assert!(msaa.second_layer_bytes() > 0);
    // Before this frame's resolve, and finish before begin.
    let text = one_line(msaa.begin_second_layer(gl, output).unwrap_err());
    assert!(text.contains("resolve"), "{text}");
    let text = one_line(msaa.finish_second_layer(gl, output).unwrap_err());
    assert!(text.contains("begin_second_layer"), "{text}");
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    assert!(msaa.begin_second_layer(gl, output).unwrap());
    // Twice, a resolve in between, or another output: refused.
    let text = one_line(msaa.begin_second_layer(gl, output).unwrap_err());
    assert!(text.contains("twice"), "{text}");
    let text = one_line(msaa.resolve(gl, &frame()).unwrap_err());
    assert!(text.contains("between"), "{text}");
    let text = one_line(msaa.finish_second_layer(gl, None).unwrap_err());
    assert!(text.contains("another output"), "{text}");
    msaa.finish_second_layer(gl, output).unwrap();
    // A normal attachment that is not there is refused by name, and the
    // retrofit keeps its two layers.
    let bad = RetrofitOptions {
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(7),
            encoding: NormalEncoding::Unorm,
        }),
        ..two.clone()
    };
    let text = one_line(msaa.set_options(gl, &bad).unwrap_err());
    assert!(
        text.contains("GL_COLOR_ATTACHMENT7") && text.contains("nothing is attached"),
        "{text}"
    );
    assert_eq!(msaa.options(), &two);
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// A host with as many colours as the context has draw buffers, less one,
/// has two layers at construction and by `set_options` (the second
/// resolve, which writes every colour, the coverage and the depth, takes
/// two draws there), where it was once refused.
#[test]
fn two_layers_take_a_host_without_draw_buffers_to_spare() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let max = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) } as u32;
    let colours: Vec<Texture2d> = (0..max - 1)
        .map(|k| Texture2d::new(gl, &format!("wide host {k}"), Format::Rgba8, 16, 16).unwrap())
        .collect();
    let depth = Texture2d::new(gl, "wide host depth", Format::Depth32f, 16, 16).unwrap();
    let mut attachments: Vec<(Attachment, TextureRef)> = colours
        .iter()
        .enumerate()
        .map(|(k, t)| (Attachment::Color(k as u32), TextureRef::from(t)))
        .collect();
    attachments.push((Attachment::Depth, TextureRef::from(&depth)));
    let draw: Vec<Option<u32>> = (0..max - 1).map(Some).collect();
    let fbo = Framebuffer::new(gl, "wide host", &attachments, &draw).unwrap();
    let two = RetrofitOptions {
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        ..RetrofitOptions::default()
    };
    // Once refused for want of draw buffers: the second layer's resolve
    // now takes as many draws as its outputs need.
    MsaaRetrofit::new(gl, fbo.raw(), &two)
        .expect("two layers where one is accepted")
        .destroy(gl);
    let mut msaa = MsaaRetrofit::new(gl, fbo.raw(), &RetrofitOptions::default()).unwrap();
    msaa.set_options(gl, &two)
        .expect("two layers where one is accepted");
    assert_eq!(msaa.options(), &two);
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    fbo.destroy(gl);
    for t in colours {
        t.destroy(gl);
    }
    depth.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// The two lit layers mix by the second layer's coverage in the domain the
/// host chose, on an HDR (RGBA16F) and an LDR (RGBA8) output: `Auto` is
/// the sRGB-encoded display values' domain on the second (on the first it
/// is refused: `nothing_declared_into_a_float_output_is_refused`), `Curve`
/// is the host's own curve. Pixels the second layer does not cover keep the first
/// lighting bit for bit. The toy host lights by a gain of 6, so the HDR
/// values are where the domains differ.
#[test]
fn the_lit_layers_mix_by_coverage_in_the_chosen_domain() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    const GAIN: f32 = 6.0;
    let curve = "vec3 dmsaa_curve(vec3 x) { return x / (1.0 + x); }\n\
                 vec3 dmsaa_curve_inverse(vec3 y) { return y / max(1.0 - y, vec3(1e-6)); }\n";
    type Domain = fn([f64; 3]) -> [f64; 3];
    let identity: Domain = |x| x;
    let max3 = |x: [f64; 3]| x[0].max(x[1]).max(x[2]);
    let tonemap: (Domain, Domain) = (
        |x| x.map(|c| c / (1.0 + x[0].max(x[1]).max(x[2]).max(0.0))),
        |y| y.map(|c| c / (1.0 - y[0].max(y[1]).max(y[2])).max(1e-6)),
    );
    let reinhard: (Domain, Domain) = (
        |x| x.map(|c| c / (1.0 + c)),
        |y| y.map(|c| c / (1.0 - c).max(1e-6)),
    );
    // sRGB-encoded display values: decoded to linear light and back.
    let srgb: (Domain, Domain) = (
        |x| x.map(|c| common::srgb::decode((c.clamp(0.0, 1.0) * 255.0).round() as u8)),
        |y| y.map(|l| common::srgb::encode(l) / 255.0),
    );
    let cases: [(Format, LayerMix, (Domain, Domain)); 6] = [
        (Format::Rgba16f, LayerMix::Tonemapped, tonemap),
        (Format::Rgba16f, LayerMix::Linear, (identity, identity)),
        (Format::Rgba16f, LayerMix::Curve(curve.into()), reinhard),
        (Format::Rgba8, LayerMix::Auto, srgb),
        (Format::Rgba8, LayerMix::SrgbEncoded, srgb),
        (Format::Rgba8, LayerMix::Linear, (identity, identity)),
    ];
    for (format, layer_mix, (to, from)) in cases {
        let label = format!("{} {layer_mix:?}", format.name());
        let (output, fbo) = lit_output(gl, format);
        let options = RetrofitOptions {
            position_attachment: Some(ColorAttachment(1)),
            resolve: ResolveSettings {
                layers: 2,
                ..ResolveSettings::default()
            },
            normal_attachment: Some(NormalAttachment {
                attachment: ColorAttachment(2),
                encoding: NormalEncoding::Xyz,
            }),
            layer_mix: layer_mix.clone(),
            ..RetrofitOptions::default()
        };
        let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
        let coverage = readback
            .read(gl, msaa.second_layer_coverage().unwrap(), 1)
            .unwrap();
        host.light(gl, fbo.raw(), GAIN);
        let lit_first = readback.read(gl, TextureRef::from(&output), 1).unwrap();
        assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
        // The host's unchanged lighting, a second time, on the second layer.
        host.light(gl, fbo.raw(), GAIN);
        let lit_second = readback.read(gl, TextureRef::from(&output), 1).unwrap();
        msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
        let mixed = readback.read(gl, TextureRef::from(&output), 1).unwrap();
        let tolerance = |v: f64| match format {
            Format::Rgba8 => 1.5 / 255.0,
            _ => 1e-4 + 2e-3 * v.abs(),
        };
        let (mut covered, mut bad, mut domain_matters) = (0, Vec::new(), false);
        for y in 0..H {
            for x in 0..W {
                let a = f64::from(coverage.get(0, x, y)[0]);
                let (f, s, got) = (
                    lit_first.get(0, x, y),
                    lit_second.get(0, x, y),
                    mixed.get(0, x, y),
                );
                if a == 0.0 {
                    if got != f {
                        bad.push(format!("({x},{y}) uncovered: {got:?}, was {f:?}"));
                    }
                    continue;
                }
                covered += 1;
                let rgb = |v: [f32; 4]| [v[0], v[1], v[2]].map(f64::from);
                let (tf, ts) = (to(rgb(f)), to(rgb(s)));
                let want = from([0, 1, 2].map(|c| tf[c] + (ts[c] - tf[c]) * a));
                let linear = [0, 1, 2].map(|c| rgb(f)[c] + (rgb(s)[c] - rgb(f)[c]) * a);
                domain_matters |= (0..3).any(|c| (want[c] - linear[c]).abs() > 0.05);
                let alpha = f64::from(f[3]) + (f64::from(s[3]) - f64::from(f[3])) * a;
                let ok = (0..3).all(|c| (f64::from(got[c]) - want[c]).abs() <= tolerance(want[c]))
                    && (f64::from(got[3]) - alpha).abs() <= tolerance(alpha);
                if !ok {
                    bad.push(format!(
                        "({x},{y}) α {a}: {got:?}, want {want:?} (first {f:?}, second {s:?}, max3 {})",
                        max3(rgb(s))
                    ));
                }
            }
        }
        assert!(
            covered >= 20,
            "{label}: only {covered} pixels have a second layer"
        );
        assert!(
            bad.is_empty(),
            "{label}: {} pixels wrong: {:#?}",
            bad.len(),
            &bad[..bad.len().min(6)]
        );
        // Where the domain is not linear the check must tell it from linear.
        let linear = to([2.0, 0.5, 0.1]) == [2.0, 0.5, 0.1];
        assert!(
            linear || domain_matters,
            "{label}: no pixel where the domain changes the mix"
        );
        msaa.destroy(gl);
        fbo.destroy(gl);
        output.destroy(gl);
    }
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// Two layers (and the forward target) into a floating-point output with
/// nothing declared: the tonemap that decides the mix's domain is the
/// host's, which GL state cannot tell, so `begin_second_layer` and
/// `begin_forward` return `Error::LayerMixUndeclared` naming the
/// declarations, having changed no GL state and left no GL error; the
/// same retrofit, its mix declared, then runs the second layer.
#[test]
fn nothing_declared_into_a_float_output_is_refused() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let (output, fbo) = lit_output(gl, Format::Rgba16f);
    let mut options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        ..RetrofitOptions::default()
    };
    assert_eq!(options.layer_mix, LayerMix::Auto, "the default");
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    host.light(gl, fbo.raw(), 1.0);
    let refused = |e: Error, call: &str| {
        let message = e.to_string();
        assert!(
            matches!(e, Error::LayerMixUndeclared { format: "RGBA16F" }),
            "{call}: {e:?}"
        );
        for named in [
            "LayerMix::Curve",
            "LayerMix::Tonemapped",
            "LayerMix::Linear",
        ] {
            assert!(
                message.contains(named),
                "{call}: {message} names no {named}"
            );
        }
    };
    let state = crate::common::gl_state::GlState::capture(gl);
    refused(
        msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap_err(),
        "begin_second_layer",
    );
    refused(
        msaa.begin_forward(gl, Some(fbo.raw())).unwrap_err(),
        "begin_forward",
    );
    let changed = state.differences(&crate::common::gl_state::GlState::capture(gl));
    assert!(
        changed.is_empty(),
        "the refusals changed GL state: {changed:?}"
    );
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    // Declared, the same retrofit runs the second layer.
    options.layer_mix = LayerMix::Tonemapped;
    msaa.set_options(gl, &options).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    host.light(gl, fbo.raw(), 1.0);
    assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
    host.light(gl, fbo.raw(), 1.0);
    msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
    msaa.destroy(gl);
    fbo.destroy(gl);
    output.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// `restore_first_layer: Nothing`, for hosts that read nothing of their
/// G-buffer after lighting, and `DepthAndStencil`, for hosts that only
/// depth-test against it: the lit image is bit for bit the one with the
/// first layer restored; without a restore the host's textures and depth
/// hold the second layer afterwards instead of the first, with the depth
/// alone restored its colours do and its depth is the first layer's; the
/// option changes without a rebuild, and switching it between `begin` and
/// `finish` restores exactly what `begin` saved.
#[test]
fn without_restoring_the_first_layer_the_lit_image_is_the_same() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    let (output, fbo) = lit_output(gl, Format::Rgba16f);
    let options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        layer_mix: LayerMix::Tonemapped, // an RGBA16F lit output: its tonemap declared
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let gbuffer = |readback: &mut Readback| {
        let mut planes: Vec<Vec<f32>> = [host.color(), host.position(), host.normal()]
            .iter()
            .map(|t| readback.read(gl, TextureRef::from(*t), 1).unwrap().data)
            .collect();
        planes.push(
            readback
                .read(gl, TextureRef::from(&host.depth), 1)
                .unwrap()
                .data,
        );
        planes
    };
    // One frame with the three calls; `flip` sets the option between begin
    // and finish. Returns the mixed image, the host's G-buffer before begin
    // and after finish, and the second layer's G-buffer.
    let mut frame_with =
        |msaa: &mut MsaaRetrofit, restore: FirstLayerRestore, flip: Option<FirstLayerRestore>| {
            let mut options = options.clone();
            options.restore_first_layer = restore;
            msaa.set_options(gl, &options).unwrap();
            unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
            host.draw(gl, &projection(), false);
            msaa.resolve(gl, &frame()).unwrap();
            host.light(gl, fbo.raw(), 1.0);
            let first = gbuffer(&mut readback);
            assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
            if let Some(flipped) = flip {
                options.restore_first_layer = flipped;
                msaa.set_options(gl, &options).unwrap();
            }
            host.light(gl, fbo.raw(), 1.0);
            msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
            let mixed = readback
                .read(gl, TextureRef::from(&output), 1)
                .unwrap()
                .data;
            let after = gbuffer(&mut readback);
            let (colors, depth) = msaa.second_layer_gbuffer().unwrap();
            let mut second: Vec<Vec<f32>> = colors
                .iter()
                .map(|t| readback.read(gl, *t, 1).unwrap().data)
                .collect();
            second.push(readback.read(gl, depth, 1).unwrap().data);
            (mixed, first, after, second)
        };
    // How many values of two sets of planes differ (bit for bit).
    let differ = |a: &[Vec<f32>], b: &[Vec<f32>]| -> usize {
        a.iter()
            .zip(b)
            .map(|(p, q)| {
                p.iter()
                    .zip(q)
                    .filter(|(x, y)| x.to_bits() != y.to_bits())
                    .count()
            })
            .sum()
    };
    use FirstLayerRestore::{DepthAndStencil, Everything, Nothing};
    let (mixed_restored, first, after, _) = frame_with(&mut msaa, Everything, None);
    assert_eq!(
        differ(&after, &first),
        0,
        "restored: the first layer is back"
    );
    let (mixed_kept, first, after, second) = frame_with(&mut msaa, Nothing, None);
    assert_eq!(
        differ(
            std::slice::from_ref(&mixed_kept),
            std::slice::from_ref(&mixed_restored)
        ),
        0,
        "the lit image does not change"
    );
    assert!(
        differ(&after, &first) > 0,
        "the second layer differs from the first somewhere"
    );
    assert_eq!(
        differ(&after[..3], &second[..3]),
        0,
        "not restored: the host's colours are the second layer's"
    );
    // The depth alone: it is the first layer's again, the colours are the
    // second layer's.
    let (mixed, first, after, second) = frame_with(&mut msaa, DepthAndStencil, None);
    assert_eq!(differ(&[mixed], std::slice::from_ref(&mixed_restored)), 0);
    assert_eq!(differ(&after[3..], &first[3..]), 0, "the depth is back");
    assert!(
        differ(&after[..3], &first[..3]) > 0,
        "the second layer's colours differ from the first's somewhere"
    );
    assert_eq!(
        differ(&after[..3], &second[..3]),
        0,
        "depth alone restored: the host's colours are the second layer's"
    );
    // Turned off after begin: begin saved, so finish restores.
    let (_, first, after, _) = frame_with(&mut msaa, Everything, Some(Nothing));
    assert_eq!(differ(&after, &first), 0);
    // Turned on after begin: nothing was saved, so nothing is put back.
    let (mixed, first, after, _) = frame_with(&mut msaa, Nothing, Some(Everything));
    assert_eq!(differ(&[mixed], std::slice::from_ref(&mixed_restored)), 0);
    assert!(differ(&after, &first) > 0);
    // The depth saved at begin, everything asked for at finish: the depth
    // alone comes back.
    let (_, first, after, _) = frame_with(&mut msaa, DepthAndStencil, Some(Everything));
    assert_eq!(differ(&after[3..], &first[3..]), 0);
    assert!(differ(&after[..3], &first[..3]) > 0);
    msaa.destroy(gl);
    fbo.destroy(gl);
    output.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before);
}

/// The second layer's selection, used as a host would (attached as the
/// depth-stencil of its own framebuffer, a pass drawn with
/// `GL_EQUAL 1`), marks exactly the pixels whose coverage is above 0, on a
/// frame where some pixels have a second cluster and most do not; with
/// one layer there is none.
#[test]
fn the_second_layer_selection_marks_exactly_the_covered_pixels() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let host = host(gl);
    let mut readback = Readback::new(gl).unwrap();
    let one = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        ..RetrofitOptions::default()
    };
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &one).unwrap();
    assert!(msaa.second_layer_selection().is_none());
    let two = RetrofitOptions {
        resolve: ResolveSettings {
            layers: 2,
            ..ResolveSettings::default()
        },
        ..one
    };
    msaa.set_options(gl, &two).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    let selection = msaa
        .second_layer_selection()
        .expect("two layers on GL 3.2+ with draw buffers to spare: a selection");
    let marks = Texture2d::new(gl, "marks", Format::R8, W, H).unwrap();
    let fbo = Framebuffer::new(
        gl,
        "a host's pass with the selection",
        &[
            (Attachment::Color(0), TextureRef::from(&marks)),
            (Attachment::DepthStencil, selection),
        ],
        &[Some(0)],
    )
    .unwrap();
    // Clears and blits ignore the stencil test: a draw, as a host's
    // lighting pass is (no depth test: the selection's depth is not defined).
    let white = deferred_msaa_lab::gl::FullscreenPass::new(
        gl,
        "white",
        &deferred_msaa_lab::gl::ShaderSource::new().part(
            "white.frag",
            "out vec4 o_color;\nvoid main() { o_color = vec4(1.0); }\n",
        ),
        &[("o_color", 0)],
    )
    .unwrap();
    let vao = deferred_msaa_lab::gl::VertexArray::new(gl, "white").unwrap();
    white.begin(gl, &fbo);
    unsafe {
        gl.viewport(0, 0, W as i32, H as i32);
        gl.clear_color(0.0, 0.0, 0.0, 0.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
        gl.enable(glow::STENCIL_TEST);
        gl.stencil_func(
            glow::EQUAL,
            i32::from(deferred_msaa::second_layer::SECOND_LAYER_SELECTED),
            0xFF,
        );
        gl.stencil_mask(0);
    }
    white.draw(gl, &vao);
    unsafe {
        gl.disable(glow::STENCIL_TEST);
        gl.stencil_mask(0xFF);
    }
    let marked = readback.read(gl, TextureRef::from(&marks), 1).unwrap();
    let coverage = readback
        .read(gl, msaa.second_layer_coverage().unwrap(), 1)
        .unwrap();
    let (mut covered, mut mismatched) = (0, Vec::new());
    for y in 0..H {
        for x in 0..W {
            let c = coverage.get(0, x, y)[0] > 0.0;
            let m = marked.get(0, x, y)[0] > 0.5;
            covered += usize::from(c);
            if c != m {
                mismatched.push((x, y, c));
            }
        }
    }
    assert!(
        covered > 0 && covered < (W * H) as usize / 2,
        "{covered} covered pixels"
    );
    let marked_count = (0..H)
        .flat_map(|y| (0..W).map(move |x| (x, y)))
        .filter(|&(x, y)| marked.get(0, x, y)[0] > 0.5)
        .count();
    assert!(
        mismatched.is_empty(),
        "{} pixels where the selection and coverage > 0 differ ({covered} covered, {marked_count} marked), first {:?}",
        mismatched.len(),
        &mismatched[..mismatched.len().min(5)]
    );
    white.destroy(gl);
    vao.destroy(gl);
    fbo.destroy(gl);
    marks.destroy(gl);
    msaa.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before);
}

/// Two layers wherever one layer is accepted: hosts with 5, 6, 7 and 8
/// colour attachments and a `DEPTH24_STENCIL8` texture (the last copying
/// its stencil by blit, which needs no reference index, as one layer then
/// needs), at the context's own draw-buffer limit (8 on llvmpipe). Where
/// the host's colours and the second layer's coverage, depth and seed
/// sample need more draw buffers than that, the second resolve takes
/// several draws; every attachment of the second layer, its coverage and
/// its depth still equal the CPU reference's, and the lit layers mix.
#[test]
fn two_layers_on_wide_gbuffers_at_the_contexts_draw_buffers() {
    use deferred_msaa_lab::resolve::StencilCopy;
    use deferred_msaa_testkit::host::Output;
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let draw_buffers = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) };
    let outputs: Vec<(Output, Format)> = vec![
        (Output::Color, Format::Rgba16f),
        (Output::Position, Format::Rgba32f),
        (Output::Normal, Format::Rgba16f),
        (Output::Specular, Format::Rgba8),
        (Output::Emissive, Format::Rgba16f),
        (Output::Material, Format::Rgba8),
        (Output::LinearDepth, Format::R16f),
        (Output::Tint, Format::Rgba8),
    ];
    let mut readback = Readback::new(gl).unwrap();
    for colours in 5..=8usize {
        let label = format!(
            "{colours} colour attachments and DEPTH24_STENCIL8, {draw_buffers} draw buffers"
        );
        let mut host = Host::with_outputs(gl, W, H, &outputs[..colours], Format::Depth24Stencil8)
            .expect("the wide host");
        host.set_triangles(gl, &triangles()).unwrap();
        // Every colour point used and a stencil: the copy by index needs
        // one more output than the context has, so that host copies by blit.
        let stencil = if colours as i32 >= draw_buffers {
            StencilCopy::Blit
        } else {
            StencilCopy::Auto
        };
        let one_layer = RetrofitOptions {
            position_attachment: Some(ColorAttachment(1)),
            normal_attachment: Some(NormalAttachment {
                attachment: ColorAttachment(2),
                encoding: NormalEncoding::Xyz,
            }),
            stencil,
            ..RetrofitOptions::default()
        };
        MsaaRetrofit::new(gl, host.fbo.raw(), &one_layer)
            .unwrap_or_else(|e| panic!("{label}: one layer refused: {e}"))
            .destroy(gl);
        let options = RetrofitOptions {
            resolve: ResolveSettings {
                layers: 2,
                ..ResolveSettings::default()
            },
            layer_mix: LayerMix::Tonemapped, // an RGBA16F lit output: its tonemap declared
            ..one_layer
        };
        let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options)
            .unwrap_or_else(|e| panic!("{label}: two layers refused where one is accepted: {e}"));
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
        host.draw(gl, &projection(), false);
        msaa.resolve(gl, &frame()).unwrap();
        let (depth_ref, color_refs, _) = msaa.inputs().unwrap();
        let samples: Vec<_> = color_refs
            .iter()
            .map(|t| readback.read(gl, *t, 1).unwrap())
            .collect();
        let depth_samples = readback.read(gl, depth_ref, 1).unwrap();
        let (layer_refs, layer_depth_ref) = msaa.second_layer_gbuffer().unwrap();
        let layer: Vec<_> = layer_refs
            .iter()
            .map(|t| readback.read(gl, *t, 1).unwrap())
            .collect();
        let layer_depth = readback.read(gl, layer_depth_ref, 1).unwrap();
        let coverage = readback
            .read(gl, msaa.second_layer_coverage().unwrap(), 1)
            .unwrap();
        let cpu = msaa.cpu_reference(&frame()).unwrap();
        let (mut bad, mut covered) = (Vec::new(), 0);
        for y in 0..H {
            for x in 0..W {
                let px = deferred_msaa_lab::readback::pixel_samples(&depth_samples, &samples, x, y);
                let want = cpu.resolve_second_layer_at(
                    &px,
                    Some(PixelPlace {
                        x,
                        y,
                        width: W,
                        height: H,
                    }),
                );
                if want.ambiguous {
                    continue;
                }
                let a = f64::from(coverage.get(0, x, y)[0]);
                if (a - want.coverage).abs() > 1e-3 {
                    bad.push(format!("({x},{y}) coverage: gpu {a} cpu {}", want.coverage));
                }
                if want.coverage == 0.0 {
                    continue;
                }
                covered += 1;
                for (k, plane) in layer.iter().enumerate() {
                    let got = plane.get(0, x, y);
                    let expected = want.attachments[k];
                    let format = outputs[k].1;
                    let channels = format
                        .properties()
                        .rgba_bits
                        .iter()
                        .filter(|&&b| b > 0)
                        .count();
                    let close = |c: usize| {
                        let e = expected[c];
                        let g = f64::from(got[c]);
                        match format {
                            Format::Rgba32f => (g - e).abs() <= 1e-4 * (1.0 + e.abs()),
                            Format::Rgba8 => (g - e).abs() <= 1.0 / 255.0,
                            _ => half_close(got[c], e),
                        }
                    };
                    if !(0..channels).all(close) {
                        bad.push(format!(
                            "({x},{y}) second layer attachment {k} ({}): gpu {got:?} cpu {expected:?}",
                            format.name()
                        ));
                    }
                }
                let d = f64::from(layer_depth.get(0, x, y)[0]);
                if (d - want.depth).abs() > 1e-6 {
                    bad.push(format!("({x},{y}) depth: gpu {d} cpu {}", want.depth));
                }
            }
        }
        eprintln!("{label}: {covered} pixels with a second layer, every attachment checked");
        assert!(
            covered >= 20,
            "{label}: only {covered} pixels with a second layer"
        );
        assert!(
            bad.is_empty(),
            "{label}: {} mismatches: {:#?}",
            bad.len(),
            &bad[..bad.len().min(8)]
        );
        // The three calls around the host's lighting, as any host makes them.
        let (output, fbo) = lit_output(gl, Format::Rgba16f);
        host.light(gl, fbo.raw(), 1.0);
        assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
        host.light(gl, fbo.raw(), 1.0);
        msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
        assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR, "{label}");
        msaa.destroy(gl);
        fbo.destroy(gl);
        output.destroy(gl);
        host.destroy(gl);
    }
    readback.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}

/// Attachments the second layer need not carry
/// (`RetrofitOptions::second_layer_omits`): a host of seven colour
/// attachments and a depth-stencil texture whose lighting does not read two
/// of them names them; the second resolve then fits one draw; during the
/// second lighting the omitted ones hold the first layer's values and the
/// carried ones the second layer's; naming an attachment the host lacks is
/// refused in one line.
#[test]
fn the_second_layer_leaves_out_the_attachments_the_host_names() {
    use deferred_msaa_testkit::host::Output;
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let before = live_objects();
    let outputs = [
        (Output::Color, Format::Rgba16f),
        (Output::Position, Format::Rgba32f),
        (Output::Normal, Format::Rgba16f),
        (Output::Specular, Format::Rgba8),
        (Output::Emissive, Format::Rgba16f),
        (Output::Material, Format::Rgba8),
        (Output::Tint, Format::Rgba8),
    ];
    let mut host = Host::with_outputs(gl, W, H, &outputs, Format::Depth24Stencil8).unwrap();
    host.set_triangles(gl, &triangles()).unwrap();
    let mut options = RetrofitOptions {
        position_attachment: Some(ColorAttachment(1)),
        normal_attachment: Some(NormalAttachment {
            attachment: ColorAttachment(2),
            encoding: NormalEncoding::Xyz,
        }),
        second_layer_omits: vec![ColorAttachment(5), ColorAttachment(6)],
        layer_mix: LayerMix::Tonemapped, // an RGBA16F lit output: its tonemap declared
        ..RetrofitOptions::default()
    };
    options.resolve.layers = 2;
    let mut msaa = MsaaRetrofit::new(gl, host.fbo.raw(), &options).unwrap();
    let mut readback = Readback::new(gl).unwrap();
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(msaa.begin_frame(gl).unwrap())) };
    host.draw(gl, &projection(), false);
    msaa.resolve(gl, &frame()).unwrap();
    let first: Vec<_> = host
        .colors
        .iter()
        .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1).unwrap().data)
        .collect();
    let coverage = readback
        .read(gl, msaa.second_layer_coverage().unwrap(), 1)
        .unwrap();
    let covered = coverage.data.chunks(4).filter(|p| p[0] > 0.0).count();
    assert!(covered >= 20, "only {covered} pixels with a second layer");
    let (output, fbo) = lit_output(gl, Format::Rgba16f);
    host.light(gl, fbo.raw(), 1.0);
    assert!(msaa.begin_second_layer(gl, Some(fbo.raw())).unwrap());
    // The host's images as its second lighting sees them.
    let during: Vec<_> = host
        .colors
        .iter()
        .map(|(_, t)| readback.read(gl, TextureRef::from(t), 1).unwrap().data)
        .collect();
    for k in [5, 6] {
        assert!(
            during[k] == first[k],
            "omitted attachment {k} does not hold the first layer during the second lighting"
        );
    }
    assert!(
        during[0] != first[0],
        "a carried attachment holds the first layer during the second lighting"
    );
    host.light(gl, fbo.raw(), 1.0);
    msaa.finish_second_layer(gl, Some(fbo.raw())).unwrap();
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
    msaa.destroy(gl);
    // An attachment the host lacks.
    let text = MsaaRetrofit::new(
        gl,
        host.fbo.raw(),
        &RetrofitOptions {
            second_layer_omits: vec![ColorAttachment(7)],
            ..options.clone()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        text.contains("second_layer_omits") && text.contains("nothing is attached there"),
        "{text}"
    );
    fbo.destroy(gl);
    output.destroy(gl);
    readback.destroy(gl);
    host.destroy(gl);
    assert_eq!(live_objects(), before, "GL objects leaked");
}
