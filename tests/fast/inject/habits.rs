//! The tutorial program written with engines' habits under `inject`
//! (`inject_tutorial.cpp`'s flags): light volumes, lighting in two passes,
//! the camera in a uniform block or as one view-projection uniform. Each
//! is run in-source and under inject, its frame compared
//! (`an_unmodified_glfw_program_under_inject_draws_the_in_source_frame`).

use super::{Run, capi, cli, frame, own_frame};
use std::path::Path;
use std::process::Command;

/// What the habits' runs share with the test that built the programs.
pub(super) struct Setup<'a> {
    pub(super) build: &'a Path,
    pub(super) out: &'a Path,
    pub(super) in_source: &'a Path,
    pub(super) plain: &'a Path,
    pub(super) display: String,
    /// The shipped tutorial profile's text.
    pub(super) text: &'a str,
    /// That profile at two layers.
    pub(super) two_layers: &'a Path,
}

/// Every habit's run.
pub(super) fn run(setup: &Setup<'_>) {
    // Light volumes (`--light-volumes`): an ambient quad, then one additive
    // quad per light, each light's values set as uniforms before its draw,
    // blending on and depth writes off. Two layers replay each draw with
    // its own uniforms and blend and depth state, after the pass's colour
    // clear: the in-source frame (its second lighting cleared and drawn the
    // same way), bit for bit.
    let volumes: &[&str] = &["--light-volumes"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-light-volumes",
        volumes,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, light volumes, tutorial two layers".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: volumes,
        in_source_args: &["--tutorial-options", "--two-layers"],
        profile: Some(setup.two_layers),
        resolves: 2,
        calls: &["the second layer (begin, the replayed lighting, finish) 2"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    // The same light volumes with each light's values in a uniform block
    // (`--light-block`), written with glBufferSubData before its draw: the
    // replay writes each light's bytes again before its draw, the in-source
    // frame bit for bit.
    let block: &[&str] = &["--light-volumes", "--light-block"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-light-block",
        block,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, light volumes from a uniform block, tutorial two layers".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: block,
        in_source_args: &["--tutorial-options", "--two-layers"],
        profile: Some(setup.two_layers),
        resolves: 2,
        calls: &["the second layer (begin, the replayed lighting, finish) 2"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    // An HDR lit target (`--float-lit`: RGBA16F, blitted to the screen),
    // nothing declared: the forward target, on by default, is refused for
    // it (its tonemap unknown) and said once; the retrofit goes on, the
    // cubes single-sampled, the frame the in-source one (whose
    // dmsaa_begin_forward is refused alike).
    let float_lit: &[&str] = &["--float-lit"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-float-lit",
        float_lit,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, float lit target, default options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: float_lit,
        in_source_args: &[],
        profile: None,
        resolves: 2,
        // Asked once, refused, not asked again.
        calls: &["dmsaa_begin_forward 1"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    let said = capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--")
            .arg(setup.plain)
            .arg(setup.out.join("float-lit-said.rgba"))
            .args(float_lit)
            .env("DISPLAY", &setup.display),
        "deferred-msaa inject, float lit target",
    );
    let stderr = String::from_utf8_lossy(&said.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("deferred-msaa inject: "))
        .collect();
    assert!(
        lines.len() == 2
            && lines[0].contains("retrofitting framebuffer")
            && lines[1].contains("dmsaa_begin_forward failed")
            && lines[1].contains("layer_mix")
            && lines[1].contains("single-sampled"),
        "the refused forward target, said once:\n{stderr}"
    );
    // `--learn` on the program with its camera as one `viewProjection`
    // uniform: no uniform is named `projection`, and the learned profile
    // names the product, from its value (a perspective projection times a
    // view), as `view_projection_uniform`.
    let learned = setup.build.join("learned-view-projection.toml");
    capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--learn")
            .arg(&learned)
            .arg("--")
            .arg(setup.plain)
            .arg(setup.out.join("learn-view-projection.rgba"))
            .arg("--view-projection")
            .env("DISPLAY", &setup.display),
        "deferred-msaa inject --learn, view-projection uniform",
    );
    let text = std::fs::read_to_string(&learned).expect("--learn wrote no profile");
    assert!(
        text.contains("view_projection_uniform = \"viewProjection\"")
            && !text.contains("\nuniform = ")
            && !text.contains("\nview_uniform = "),
        "the learned profile does not name the product:\n{text}"
    );
    // The same lights in two passes (`--two-pass-lighting`): added into an
    // accumulation target of the program's, then composed into
    // framebuffer 0. With the profile's `[lighting] passes = 2`, the replay
    // clears and fills the accumulation target again and composes into the
    // own target: the in-source frame, bit for bit; left at one pass, the
    // accumulation alone would be the second lighting.
    let two_pass_profile = setup.build.join("tutorial-two-pass.toml");
    std::fs::write(
        &two_pass_profile,
        format!(
            "{}\n[lighting]\npass = 1\npasses = 2\n",
            std::fs::read_to_string(setup.two_layers).expect("the two-layer profile")
        ),
    )
    .expect("writing the two-pass profile");
    let two_pass: &[&str] = &["--two-pass-lighting", "--light-volumes"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-two-pass",
        two_pass,
        &setup.display,
    );
    let run = Run {
        what: "GLFW GLX, two-pass light volumes, tutorial two layers".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: two_pass,
        in_source_args: &["--tutorial-options", "--two-layers"],
        profile: Some(&two_pass_profile),
        resolves: 2,
        calls: &["the second layer (begin, the replayed lighting, finish) 2"],
    };
    run.compare(setup.in_source, setup.plain, &own, "GLX");
    let one_pass = setup.out.join("two-pass-as-one.rgba");
    capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--profile")
            .arg(setup.two_layers)
            .arg("--")
            .arg(setup.plain)
            .arg(&one_pass)
            .args(two_pass)
            .env("DISPLAY", &setup.display),
        "deferred-msaa inject, the two-pass lighting left as one pass",
    );
    let expected = setup.out.join(format!(
        "{}-in-source.rgba",
        run.what.replace([' ', ','], "-")
    ));
    assert!(
        frame(&one_pass) != frame(&expected),
        "the two-pass lighting replayed as one pass drew the in-source frame: the test proves nothing"
    );
    // The camera in a uniform block (`--camera-block`: no shader has a
    // `projection` uniform): without a profile the camera is found in the
    // block by the matrices written there (a perspective projection at byte
    // 0, a rigid view at 64), said on the retrofit's line, and the frame is
    // the in-source one with the default options, bit for bit; with the
    // tutorial profile naming the block's binding and the view's offset,
    // the matrices are read from the buffer at each resolve and the frame
    // is the in-source one with those options, bit for bit.
    let camera: &[&str] = &["--camera-block"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-camera-block",
        camera,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, camera block, default options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: camera,
        in_source_args: &[],
        profile: None,
        resolves: 2,
        calls: &["the camera read from its uniform block 2"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    let found = setup.out.join("camera-block-found.rgba");
    let output = capi::run(
        cli()
            .args(["inject", "--library"])
            .arg(capi::built("libdeferred_msaa_inject", "so"))
            .arg("--")
            .arg(setup.plain)
            .arg(&found)
            .args(camera)
            .env("DISPLAY", &setup.display),
        "deferred-msaa inject, the camera in a uniform block, no profile",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(
            "the camera from the uniform block at binding 0 (projection at byte 0, view at byte 64), found by its values"
        ),
        "the camera block without a profile:\n{stderr}"
    );
    let block_profile = setup.build.join("tutorial-camera-block.toml");
    std::fs::write(
        &block_profile,
        setup.text.replace(
            "[projection]\nuniform = \"projection\"\nview_uniform = \"view\"\n",
            "[projection]\nblock_binding = 0\noffset = 0\nview_offset = 64\n",
        ),
    )
    .expect("writing the camera-block profile");
    assert!(
        std::fs::read_to_string(&block_profile).is_ok_and(|t| t.contains("block_binding")),
        "the tutorial profile's [projection] table changed: the camera-block profile was not made"
    );
    Run {
        what: "GLFW GLX, camera block, tutorial options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: camera,
        in_source_args: &["--tutorial-options"],
        profile: Some(&block_profile),
        // The camera known from the profile and the G-buffer by its
        // signature at its first bind: the first frame is retrofitted too.
        resolves: 3,
        calls: &["the camera read from its uniform block 3"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    // The camera as one `viewProjection` uniform (`--view-projection`):
    // with the profile naming it, it is taken apart into the projection and
    // the view's z row. The matrices are the product's, rounded otherwise
    // than the in-source build's own, so the frame may differ from the
    // in-source one where the depth window's weights round apart: in at
    // most 1% of the pixels, by at most 8 of 255; and where a crease's tie
    // lies within that rounding of the crease rule's threshold (which the
    // projection's terms place) it may go to the other face: in at most
    // 0.05% of them (1 pixel of 19200 here, 0 with the rule off).
    let vp: &[&str] = &["--view-projection"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-view-projection",
        vp,
        &setup.display,
    );
    let vp_profile = setup.build.join("tutorial-view-projection.toml");
    std::fs::write(
        &vp_profile,
        setup.text.replace(
            "[projection]\nuniform = \"projection\"\nview_uniform = \"view\"\n",
            "[projection]\nview_projection_uniform = \"viewProjection\"\n",
        ),
    )
    .expect("writing the view-projection profile");
    assert!(
        std::fs::read_to_string(&vp_profile).is_ok_and(|t| t.contains("view_projection_uniform")),
        "the tutorial profile's [projection] table changed: the view-projection profile was not made"
    );
    Run {
        what: "GLFW GLX, view-projection uniform, tutorial options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: vp,
        in_source_args: &["--tutorial-options"],
        profile: Some(&vp_profile),
        // The product set before the G-buffer's first bind: the first frame
        // is retrofitted too.
        resolves: 3,
        calls: &["dmsaa_resolve 3"],
    }
    .compare_within(setup.in_source, setup.plain, &own, "GLX", 0.01, 8, 0.0005);
    // What needs GL 4.5 (direct state access), after one probe of it.
    // A G-buffer made through direct state access (`--dsa`, GL 4.5:
    // glCreateFramebuffers, glTextureStorage2D, glNamedFramebufferTexture,
    // glNamedFramebufferDrawBuffers; the depth copied with
    // glBlitNamedFramebuffer): found and retrofitted as one made the old
    // way, the in-source frame bit for bit. With `--resize` the program
    // makes a new G-buffer of the new size under a new name before the last
    // frame and deletes the old one: with the tutorial profile's signature
    // the retrofit is kept and given the new one (`dmsaa_refresh_with`, as
    // the in-source build calls it) and the frame of the resize is resolved
    // too (the first is the program's own: its projection uniform is set
    // after the G-buffer's first bind).
    let dsa: &[&str] = &["--dsa"];
    let probe = Command::new(setup.plain)
        .arg(setup.out.join("dsa-probe.rgba"))
        .args(dsa)
        .env("DISPLAY", &setup.display)
        .output()
        .expect("running the tutorial program with --dsa");
    match probe.status.code() {
        Some(0) => {}
        Some(4) => {
            // A context below 4.5 (the floor's): not a missing package.
            eprintln!(
                "not run: the G-buffer made by name: {}",
                String::from_utf8_lossy(&probe.stderr).trim()
            );
            return;
        }
        _ => panic!("the tutorial program with --dsa failed: {probe:?}"),
    }
    let own = own_frame(setup.plain, setup.out, "GLX-dsa", dsa, &setup.display);
    Run {
        what: "GLFW GLX, G-buffer made by name, default options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: dsa,
        in_source_args: &[],
        profile: None,
        resolves: 2,
        calls: &["dmsaa_retrofit_new 1"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    let tutorial = setup.build.join("tutorial-dsa.toml");
    std::fs::write(&tutorial, setup.text).expect("writing the tutorial profile");
    let resized: &[&str] = &["--dsa", "--resize"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-dsa-resize",
        resized,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, G-buffer made by name anew at a resize, tutorial options".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: resized,
        in_source_args: &["--tutorial-options"],
        profile: Some(&tutorial),
        resolves: 2,
        calls: &["dmsaa_retrofit_new 1", "dmsaa_refresh_with 1"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
    // The light volumes' block written by name (`--named-writes`:
    // glNamedBufferSubData, the buffer never bound for the write, GL 4.5):
    // the replay writes each light's bytes again before its draw, the
    // in-source frame bit for bit.
    let named: &[&str] = &["--light-volumes", "--light-block", "--named-writes"];
    let own = own_frame(
        setup.plain,
        setup.out,
        "GLX-named-writes",
        named,
        &setup.display,
    );
    Run {
        what: "GLFW GLX, light volumes from a block written by name, tutorial two layers".into(),
        out: setup.out,
        display: setup.display.clone(),
        args: named,
        in_source_args: &["--tutorial-options", "--two-layers"],
        profile: Some(setup.two_layers),
        resolves: 2,
        calls: &["the second layer (begin, the replayed lighting, finish) 2"],
    }
    .compare(setup.in_source, setup.plain, &own, "GLX");
}
