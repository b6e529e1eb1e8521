//! The language's parser, types, interpreter and GLSL translation.

use super::{physical_gradient, Expression, Inputs, Slot};

fn fields() -> Vec<String> {
    vec!["pressure".into(), "u".into(), "my field".into(), "x".into()]
}

fn column_of(text: &str) -> (usize, String) {
    let e = Expression::parse(text, &fields()).expect_err(text);
    (e.column, e.message)
}

#[test]
fn errors_name_the_column() {
    // Syntax.
    assert_eq!(column_of("u +").0, 4);
    assert_eq!(column_of("(u + 1").0, 7);
    assert_eq!(column_of("u $ 2").0, 3);
    assert_eq!(column_of("u ^ 2").0, 3);
    assert!(column_of("u ^ 2").1.contains("pow"));
    assert_eq!(column_of("").0, 1);
    assert_eq!(column_of("sqrt u").0, 6);
    // Unknown names.
    let (c, m) = column_of("u * presure");
    assert_eq!(c, 5);
    assert!(m.contains("presure") && m.contains("pressure"), "{m}");
    assert_eq!(column_of("field(\"nope\")").0, 7);
    // Types: grad(u) + 1 points at the operator.
    let (c, m) = column_of("grad(u) + 1");
    assert_eq!(c, 9);
    assert!(m.contains("vector") && m.contains("scalar"), "{m}");
    assert_eq!(column_of("grad(u) * grad(u)").0, 9);
    assert_eq!(column_of("2 / grad(u)").0, 3);
    assert_eq!(column_of("u.x").0, 2);
    assert_eq!(column_of("length(u)").0, 8);
    assert_eq!(column_of("pow(u)").0, 6);
    assert_eq!(column_of("grad(x)").0, 6);
    // A vector result cannot be coloured.
    assert!(column_of("grad(u)").1.contains("vector"));
    // Numbers beyond f32.
    assert_eq!(column_of("u * 1e39").0, 5);
    // Hostile sizes.
    assert!(column_of(&"(".repeat(200)).1.contains("nested"));
    assert!(column_of(&"u+".repeat(3000)).1.contains("longer"));
}

#[test]
fn slots_follow_first_appearance() {
    let e = Expression::parse("pressure + field(\"my field\") * pressure + grad(u).x", &fields()).unwrap();
    assert_eq!(
        e.slots,
        vec![Slot::Shown, Slot::Named(0, "pressure".into()), Slot::Named(2, "my field".into())]
    );
    assert!(e.reads_shown());
    // `u` and `x` are the built-ins; the file's fields of those names are reached by field("…").
    let e = Expression::parse("field(\"u\") + field(\"x\") + x", &fields()).unwrap();
    assert_eq!(e.slots.len(), 3);
    assert!(!e.reads_shown());
    assert!(!e.uses("t"));
    assert!(Expression::parse("t * u", &fields()).unwrap().uses("t"));
}

#[test]
fn interpreter_follows_precedence_and_functions() {
    let values = [3.0, -2.0];
    let gradients = [[3.0, 4.0, 0.0], [1.0, 0.0, 0.0]];
    let variables = [[0.5, 0.0, 0.0], [2.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.25, 0.0, 0.0]];
    let inputs = Inputs { values: &values, gradients: &gradients, variables: &variables };
    let eval = |text: &str| Expression::parse(text, &fields()).unwrap().eval(&inputs);
    assert_eq!(eval("1 + 2 * 3 - 4 / 2"), 5.0);
    assert_eq!(eval("-u * -2"), 6.0);
    assert_eq!(eval("(1 + 2) * 3"), 9.0);
    assert_eq!(eval("length(grad(u))"), 5.0);
    assert_eq!(eval("dot(grad(u), grad(pressure))"), 3.0);
    assert_eq!(eval("grad(u).y - grad(u).x"), 1.0);
    assert_eq!(eval("length(grad(u) * 2 - grad(u) / 0.5)"), 0.0);
    assert_eq!(eval("u - pressure"), 5.0);
    assert_eq!(eval("x + y * z + t"), 0.5 - 2.0 + 0.25);
    assert_eq!(eval("abs(pressure) + sqrt(4) + exp(0) + log(1) + sin(0) + cos(0)"), 2.0 + 2.0 + 1.0 + 1.0);
    assert_eq!(eval("pow(2, 10) + min(1, 2) + max(1, 2)"), 1027.0);
    assert_eq!(eval("clamp(u, 0, 1) + clamp(pressure, 0, 1)"), 1.0);
    assert_eq!(eval("2.5e-1 + .5"), 0.75);
    assert!(eval("log(pressure)").is_nan());
}

#[test]
fn glsl_translation_is_parenthesised_and_typed() {
    let e = Expression::parse("length(grad(u)) - 2 * pressure / x + t", &fields()).unwrap();
    let g = e.glsl("f");
    assert!(
        g.contains(
            "return ((length(gradients[0]) - ((2e0 * values[1]) / variables[0].x)) + variables[3].x);"
        ),
        "{g}"
    );
    assert!(g.contains("float f(float values[2], vec3 gradients[2], vec3 variables[4])"), "{g}");
    // The user's text reaches the source only as a comment without '*' or '/'.
    let e = Expression::parse("u */ 1", &fields());
    assert!(e.is_err());
    let e = Expression::parse("u * 1 / 2", &fields()).unwrap();
    assert!(e.glsl("f").starts_with("// --expr u ? 1 ? 2\n"), "{}", e.glsl("f"));
}

#[test]
fn physical_gradient_inverts_the_jacobian() {
    // f = 2 x + 3 y on a sheared planar element x = ξ + 0.5 η, y = 2 η:
    // f_ξ = 2, f_η = 2·0.5 + 3·2 = 7.
    let g = physical_gradient([[1.0, 0.0, 0.0], [0.5, 2.0, 0.0]], [2.0, 7.0]);
    assert!((g[0] - 2.0).abs() < 1e-14 && (g[1] - 3.0).abs() < 1e-14 && g[2].abs() < 1e-14, "{g:?}");
    // On a tilted plane the gradient is tangential: f = s (arc length along t_ξ).
    let t = [[0.6, 0.0, 0.8], [0.0, 1.0, 0.0]];
    let g = physical_gradient(t, [1.0, 0.0]);
    assert!((g[0] - 0.6).abs() < 1e-14 && g[1].abs() < 1e-14 && (g[2] - 0.8).abs() < 1e-14, "{g:?}");
}
