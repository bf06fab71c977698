//! The property test's slow share: more than a thousand random host
//! G-buffers (`tests/common/property.rs` says what each is put through),
//! and the check that every refusal the crate states is reached by some
//! generated host, or is listed with the reason no host can reach it.

use crate::common;
use crate::common::property::{REFUSALS, UNREACHABLE, driver_dependent, run_seeds};

/// Seeds of the slow tier (the fast tier's are the first of them).
const SEEDS: std::ops::Range<u64> = 0..2000;

#[test]
#[ignore = "slow tier: cargo test --test slow -- --ignored"]
fn two_thousand_random_hosts_retrofit_or_refuse_in_one_line() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let limits = deferred_msaa_testkit::random_host::Limits::of(ctx.gl());
    let summary = run_seeds(
        &ctx,
        SEEDS,
        "--test slow property::two_thousand_random_hosts -- --ignored",
    );
    eprintln!("{}", summary.report(ctx.gl(), limits));
    for (name, why) in UNREACHABLE {
        eprintln!("not reachable: {name}: {why}");
    }
    for (name, _) in REFUSALS {
        if let Some(why) = driver_dependent(ctx.gl(), name, limits) {
            eprintln!("not reachable on this driver: {name}: {why}");
        }
    }
    assert!(
        summary.failures.is_empty(),
        "{} of the random hosts failed (seeds {:?}); each is printed above with its replay command",
        summary.failures.len(),
        summary.failures.iter().map(|f| f.0).collect::<Vec<_>>()
    );
    let live = deferred_msaa::gl::live_objects();
    assert_eq!(live.total(), 0, "the crate's GL objects left: {live:?}");
    if std::env::var_os(common::property::SEED_VAR).is_none() {
        let unreached = summary.unreached(ctx.gl(), limits);
        assert!(
            unreached.is_empty(),
            "refusals no generated host reached: {unreached:?}"
        );
    }
}
