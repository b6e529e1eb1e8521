//! The command line's own value parsers (clap parses the grammar; these are ours): image sizes,
//! colour ranges, bounded counts, cut planes, scripted keys, compression schedules, reduced
//! motions and scenario names.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[allow(dead_code)]
#[path = "../../src/cli/args.rs"]
mod args;

fuzz_target!(|data: &[u8]| {
    let Ok(s) = std::str::from_utf8(data) else { return };
    let _ = args::parse_size(s);
    let _ = args::parse_range(s);
    let _ = args::count_up_to(1_000_000)(s);
    let _ = args::image_path(s);
    let _ = s.parse::<galerkin::render::viewer::ScriptedKeys>();
    let _ = s.parse::<galerkin::fluid::reduced::CompressionSchedule>();
    let _ = s.parse::<galerkin::fluid::reduced::ReducedMotion>();
    let _ = s.parse::<galerkin::spacetime::scenario::Scenario>();
});
