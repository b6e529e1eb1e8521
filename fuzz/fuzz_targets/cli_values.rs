//! The command line's own value parsers (clap parses the grammar; these are ours): image sizes,
//! colour ranges, bounded counts, cut planes, scripted keys, compression schedules, reduced
//! motions, scenario names, and derived-field expressions (`--expr`: parsed in both scopes; a
//! parsed one is also evaluated, bounded and translated to GLSL).
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
    let _ = galerkin::spectral::render::parse_plane(s);
    let _ = s.parse::<galerkin::render::viewer::ScriptedKeys>();
    let _ = s.parse::<galerkin::fluid::reduced::CompressionSchedule>();
    let _ = s.parse::<galerkin::fluid::reduced::ReducedMotion>();
    let _ = s.parse::<galerkin::spacetime::scenario::Scenario>();
    let fields = ["pressure".to_string(), "a b".to_string()];
    if let Ok(e) = galerkin::expression::Expression::parse(s, &fields) {
        let values = [0.5, -1.0, 2.0];
        let gradients = [[1.0, 2.0, 0.0], [0.0, -1.0, 0.5], [3.0, 0.0, 0.0]];
        let variables = [[0.25, 0.0, 0.0], [-2.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.0, 0.0]];
        let inputs = galerkin::expression::Inputs { values: &values, gradients: &gradients, variables: &variables };
        let _ = e.eval(&inputs);
        let errors = galerkin::expression::InputErrors { values: &[1e-7; 3], gradients: &[1e-6; 3], variables: &[1e-7; 4] };
        let _ = e.rounding_bound(&inputs, &errors);
        let _ = e.glsl("f");
    }
    let _ = galerkin::expression::spacetime::SpacetimeExpression::new(s).map(|e| e.fragment_source());
});
