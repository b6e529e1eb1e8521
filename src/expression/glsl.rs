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
        Node::Variable(k, ty) => {
            out.push_str(&format!("variables[{k}]"));
            if *ty == super::Type::Scalar {
                out.push_str(".x");
            }
        }
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
    /// The GLSL function `float NAME(float values[F], vec3 gradients[F], vec3 variables[V])`
    /// computing this expression (F slots, V variables — scalars in x; every operation
    /// parenthesised; literals rounded to f32). The source text appears only in a comment
    /// with anything but plain printable ASCII replaced.
    pub fn glsl(&self, name: &str) -> String {
        let mut body = String::new();
        emit(&self.root, &mut body);
        let comment: String = self
            .text
            .chars()
            .map(|c| if c.is_ascii_graphic() && c != '*' && c != '/' || c == ' ' { c } else { '?' })
            .collect();
        let (f, v) = (self.slots.len(), self.variables.len().max(1));
        format!(
            "// --expr {comment}\nfloat {name}(float values[{f}], vec3 gradients[{f}], vec3 variables[{v}]) {{\n    return {body};\n}}\n"
        )
    }
}
