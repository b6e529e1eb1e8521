//! The translation of an [`Expression`] to a GLSL function, spliced into the renderer's
//! fragment shader before `spectral_element_frag.glsl` (which calls it per pixel).

use super::{BinaryOp, Expression, Node};

fn literal(v: f64) -> String {
    // f32's shortest round-trip digits, in a form GLSL reads as a float ("1e0", "2.5e-3").
    format!("{:e}", v as f32)
}

fn emit(node: &Node, out: &mut String) {
    match node {
        Node::Number(v) => out.push_str(&literal(*v)),
        Node::Coordinate(c) => {
            out.push_str("x.");
            out.push(['x', 'y', 'z'][*c]);
        }
        Node::Time => out.push('t'),
        Node::Value(k) => out.push_str(&format!("values[{k}]")),
        Node::Gradient(k) => out.push_str(&format!("gradients[{k}]")),
        Node::Negate(a) => {
            out.push_str("(-");
            emit(a, out);
            out.push(')');
        }
        Node::Component(a, c) => {
            out.push('(');
            emit(a, out);
            out.push_str(").");
            out.push(['x', 'y', 'z'][*c]);
        }
        Node::Binary(op, a, b) => {
            out.push('(');
            emit(a, out);
            out.push_str(match op {
                BinaryOp::Add => " + ",
                BinaryOp::Sub => " - ",
                BinaryOp::Mul => " * ",
                BinaryOp::Div => " / ",
            });
            emit(b, out);
            out.push(')');
        }
        Node::Call(f, args) => {
            out.push_str(f.name());
            out.push('(');
            for (k, a) in args.iter().enumerate() {
                if k > 0 {
                    out.push_str(", ");
                }
                emit(a, out);
            }
            out.push(')');
        }
    }
}

impl Expression {
    /// The GLSL function `float spectral_expression(float values[SPECTRAL_FIELDS],
    /// vec3 gradients[SPECTRAL_FIELDS], vec3 x, float t)` computing this expression (every
    /// operation parenthesised; literals rounded to f32). The source text appears only in a
    /// comment with anything but plain printable ASCII replaced.
    pub fn glsl(&self) -> String {
        let mut body = String::new();
        emit(&self.root, &mut body);
        let comment: String = self
            .text
            .chars()
            .map(|c| if c.is_ascii_graphic() && c != '*' && c != '/' || c == ' ' { c } else { '?' })
            .collect();
        format!(
            "// --expr {comment}\nfloat spectral_expression(float values[SPECTRAL_FIELDS], vec3 gradients[SPECTRAL_FIELDS], vec3 x, float t) {{\n    return {body};\n}}\n"
        )
    }
}
