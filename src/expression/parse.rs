//! The expression language's lexer and recursive-descent parser, type-checking as it goes
//! (grammar in the module documentation of `expression`):
//!
//! ```text
//! sum     = product { ("+" | "-") product }
//! product = unary { ("*" | "/") unary }
//! unary   = "-" unary | postfix
//! postfix = primary { "." ("x" | "y" | "z") }
//! primary = number | name | name "(" [ sum { "," sum } ] ")" | "(" sum ")"
//!         | "field" "(" string ")" | "grad" "(" field ")"
//! ```

use super::{
    BinaryOp, Expression, ExpressionError, Function, Node, Scope, Slot, Type, MAX_DEPTH, MAX_LENGTH,
};

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Number(f64),
    Name(String),
    Text(String),
    Symbol(char),
    End,
}

/// A token and its 1-based column.
type Located = (Token, usize);

fn lex(text: &str) -> Result<Vec<Located>, ExpressionError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let column = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let s: String = chars[start..i].iter().collect();
            let v: f64 = s
                .parse()
                .map_err(|_| ExpressionError::new(text, column, format!("{s:?} is not a number")))?;
            if !v.is_finite()
                || (v != 0.0 && (v.abs() > f64::from(f32::MAX) || v.abs() < f64::from(f32::MIN_POSITIVE)))
            {
                return Err(ExpressionError::new(
                    text,
                    column,
                    format!("{s} does not fit a 32-bit float (the device computes in f32)"),
                ));
            }
            out.push((Token::Number(v), column));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((Token::Name(chars[start..i].iter().collect()), column));
        } else if c == '"' {
            let start = i + 1;
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += 1;
            }
            if i == chars.len() {
                return Err(ExpressionError::new(text, column, "this string has no closing '\"'"));
            }
            out.push((Token::Text(chars[start..i].iter().collect()), column));
            i += 1;
        } else if "+-*/(),.".contains(c) {
            out.push((Token::Symbol(c), column));
            i += 1;
        } else if c == '^' {
            return Err(ExpressionError::new(text, column, "'^' is not an operator here: write pow(a, b)"));
        } else {
            return Err(ExpressionError::new(text, column, format!("unexpected character {c:?}")));
        }
    }
    out.push((Token::End, chars.len() + 1));
    Ok(out)
}

struct Parser<'a> {
    text: &'a str,
    tokens: Vec<Located>,
    at: usize,
    scope: &'a Scope<'a>,
    slots: Vec<Slot>,
    depth: usize,
}

/// A parsed sub-expression: its tree, type and starting column.
type Typed = (Node, Type, usize);

pub(super) fn parse(text: &str, scope: &Scope<'_>) -> Result<Expression, ExpressionError> {
    if text.chars().count() > MAX_LENGTH {
        return Err(ExpressionError::new(
            text,
            MAX_LENGTH + 1,
            format!("longer than {MAX_LENGTH} characters"),
        ));
    }
    let tokens = lex(text)?;
    let mut p = Parser { text, tokens, at: 0, scope, slots: vec![Slot::Shown], depth: 0 };
    if matches!(p.peek(), Token::End) {
        return Err(p.error(1, "the expression is empty"));
    }
    let (root, ty, column) = p.sum()?;
    if !matches!(p.peek(), Token::End) {
        return Err(p.error(p.column(), format!("unexpected {} after a complete expression", p.describe())));
    }
    if ty != Type::Scalar {
        return Err(p.error(
            column,
            "the expression is a vector; colour needs a scalar: take length(…), dot(…, …) or a component (.x)",
        ));
    }
    let variables = scope.variables.iter().map(|v| v.0.to_string()).collect();
    Ok(Expression { text: text.to_string(), root, slots: p.slots, variables })
}

impl Parser<'_> {
    fn peek(&self) -> &Token {
        &self.tokens[self.at].0
    }

    fn column(&self) -> usize {
        self.tokens[self.at].1
    }

    fn describe(&self) -> String {
        match self.peek() {
            Token::Number(v) => format!("number {v}"),
            Token::Name(n) => format!("name {n:?}"),
            Token::Text(s) => format!("string {s:?}"),
            Token::Symbol(c) => format!("{c:?}"),
            Token::End => "end of the expression".to_string(),
        }
    }

    fn error(&self, column: usize, message: impl Into<String>) -> ExpressionError {
        ExpressionError::new(self.text, column, message)
    }

    fn next(&mut self) -> Located {
        let t = self.tokens[self.at].clone();
        if self.at + 1 < self.tokens.len() {
            self.at += 1;
        }
        t
    }

    fn expect(&mut self, c: char, what: &str) -> Result<(), ExpressionError> {
        if self.peek() == &Token::Symbol(c) {
            self.next();
            Ok(())
        } else {
            Err(self.error(self.column(), format!("expected {c:?} {what}, found {}", self.describe())))
        }
    }

    fn enter(&mut self, column: usize) -> Result<(), ExpressionError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error(column, format!("nested deeper than {MAX_DEPTH} levels")));
        }
        Ok(())
    }

    fn sum(&mut self) -> Result<Typed, ExpressionError> {
        let (mut node, ty, start) = self.product()?;
        loop {
            let op = match self.peek() {
                Token::Symbol('+') => BinaryOp::Add,
                Token::Symbol('-') => BinaryOp::Sub,
                _ => return Ok((node, ty, start)),
            };
            let column = self.column();
            self.next();
            let (rhs, rty, _) = self.product()?;
            if ty != rty {
                return Err(self.error(
                    column,
                    format!(
                        "cannot {} {} and {}",
                        if op == BinaryOp::Add { "add" } else { "subtract" },
                        ty.name(),
                        rty.name()
                    ),
                ));
            }
            node = Node::Binary(op, Box::new(node), Box::new(rhs));
        }
    }

    fn product(&mut self) -> Result<Typed, ExpressionError> {
        let (mut node, mut ty, start) = self.unary()?;
        loop {
            let op = match self.peek() {
                Token::Symbol('*') => BinaryOp::Mul,
                Token::Symbol('/') => BinaryOp::Div,
                _ => return Ok((node, ty, start)),
            };
            let column = self.column();
            self.next();
            let (rhs, rty, _) = self.unary()?;
            ty = match (op, ty, rty) {
                (_, Type::Scalar, Type::Scalar) => Type::Scalar,
                (BinaryOp::Mul, Type::Scalar, Type::Vector)
                | (BinaryOp::Mul, Type::Vector, Type::Scalar)
                | (BinaryOp::Div, Type::Vector, Type::Scalar) => Type::Vector,
                (BinaryOp::Mul, _, _) => {
                    return Err(self.error(column, "cannot multiply two vectors: write dot(a, b)"))
                }
                _ => return Err(self.error(column, format!("cannot divide {} by {}", ty.name(), rty.name()))),
            };
            node = Node::Binary(op, Box::new(node), Box::new(rhs));
        }
    }

    fn unary(&mut self) -> Result<Typed, ExpressionError> {
        if self.peek() == &Token::Symbol('-') {
            let column = self.column();
            self.next();
            self.enter(column)?;
            let (node, ty, _) = self.unary()?;
            self.depth -= 1;
            return Ok((Node::Negate(Box::new(node)), ty, column));
        }
        self.postfix()
    }

    fn postfix(&mut self) -> Result<Typed, ExpressionError> {
        let (mut node, mut ty, start) = self.primary()?;
        while self.peek() == &Token::Symbol('.') {
            let column = self.column();
            self.next();
            let component = match self.next() {
                (Token::Name(n), _) if n == "x" => 0,
                (Token::Name(n), _) if n == "y" => 1,
                (Token::Name(n), _) if n == "z" => 2,
                (_, c) => return Err(self.error(c, "expected a component: x, y or z")),
            };
            if ty != Type::Vector {
                return Err(
                    self.error(column, "a component of a scalar: only vectors (grad(…)) have .x, .y, .z")
                );
            }
            node = Node::Component(Box::new(node), component);
            ty = Type::Scalar;
        }
        Ok((node, ty, start))
    }

    /// The slot of the file's field `name` (added on first use), or the shown field's.
    fn field_slot(&mut self, name: &str, column: usize, quoted: bool) -> Result<usize, ExpressionError> {
        if name == self.scope.shown && !quoted {
            return Ok(0);
        }
        let Some(index) = self.scope.fields.iter().position(|f| f == name) else {
            let mut names = vec![self.scope.shown];
            names.extend(self.scope.variables.iter().map(|v| v.0));
            let fields = if self.scope.fields.is_empty() {
                String::new()
            } else {
                format!(", and the file's fields {:?}", self.scope.fields)
            };
            return Err(self.error(
                column,
                format!(
                    "unknown name {name:?}: the names are {}, the functions ({}), grad{}{fields}",
                    names.join(", "),
                    Function::ALL.map(|f| f.1).join(", "),
                    if self.scope.fields.is_empty() { "" } else { " and field" },
                ),
            ));
        };
        let slot = Slot::Named(index, name.to_string());
        Ok(match self.slots.iter().position(|s| *s == slot) {
            Some(k) => k,
            None => {
                self.slots.push(slot);
                self.slots.len() - 1
            }
        })
    }

    /// `name` or `field("name")` as a field reference: its slot.
    fn field_reference(&mut self) -> Result<usize, ExpressionError> {
        match self.next() {
            (Token::Name(n), c) if n == "field" && self.peek() == &Token::Symbol('(') => {
                self.next();
                let slot = match self.next() {
                    (Token::Text(s), c) => self.field_slot(&s, c, true)?,
                    (_, c) => return Err(self.error(c, "field(…) takes a field's name in double quotes")),
                };
                self.expect(')', "after the field's name")?;
                let _ = c;
                Ok(slot)
            }
            (Token::Name(n), c) if self.scope.variables.iter().any(|v| v.0 == n) => Err(self.error(
                c,
                format!(
                    "{n} is a variable, not a field: grad takes a field ({} or a field's name)",
                    self.scope.shown
                ),
            )),
            (Token::Name(n), c) => self.field_slot(&n, c, false),
            (_, c) => Err(self.error(c, "expected a field (u, a field's name or field(\"name\"))")),
        }
    }

    fn primary(&mut self) -> Result<Typed, ExpressionError> {
        let (token, column) = self.next();
        match token {
            Token::Number(v) => Ok((Node::Number(v), Type::Scalar, column)),
            Token::Symbol('(') => {
                self.enter(column)?;
                let (node, ty, _) = self.sum()?;
                self.depth -= 1;
                self.expect(')', &format!("to close the '(' of column {column}"))?;
                Ok((node, ty, column))
            }
            Token::Name(name) => match name.as_str() {
                _ if name != self.scope.shown && self.scope.variables.iter().any(|v| v.0 == name) => {
                    let k = self.scope.variables.iter().position(|v| v.0 == name).unwrap_or(0);
                    let ty = self.scope.variables[k].1;
                    Ok((Node::Variable(k, ty), ty, column))
                }
                "grad" => {
                    self.expect('(', "after grad")?;
                    let slot = self.field_reference()?;
                    self.expect(')', "after grad's field")?;
                    Ok((Node::Gradient(slot), Type::Vector, column))
                }
                "field" => {
                    self.at -= 1;
                    let slot = self.field_reference()?;
                    Ok((Node::Value(slot), Type::Scalar, column))
                }
                _ => {
                    if let Some((f, params, result)) = Function::by_name(&name) {
                        self.call(f, &name, params, result, column)
                    } else {
                        let slot = self.field_slot(&name, column, false)?;
                        Ok((Node::Value(slot), Type::Scalar, column))
                    }
                }
            },
            Token::End => Err(self.error(column, "the expression ends where a value was expected")),
            other => {
                let what = match other {
                    Token::Text(s) => format!("string {s:?} (strings only name fields: field(\"name\"))"),
                    Token::Symbol(c) => format!("{c:?}"),
                    _ => "token".into(),
                };
                Err(self.error(column, format!("expected a value, found {what}")))
            }
        }
    }

    fn call(
        &mut self,
        f: Function,
        name: &str,
        params: &[Type],
        result: Type,
        column: usize,
    ) -> Result<Typed, ExpressionError> {
        self.expect('(', &format!("after the function {name}"))?;
        self.enter(column)?;
        let mut args = Vec::new();
        if self.peek() != &Token::Symbol(')') {
            loop {
                let arg_column = self.column();
                let (node, ty, _) = self.sum()?;
                let k = args.len();
                if let Some(&want) = params.get(k) {
                    if ty != want {
                        return Err(self.error(
                            arg_column,
                            format!("{name}'s argument {} must be {}, not {}", k + 1, want.name(), ty.name()),
                        ));
                    }
                }
                args.push(node);
                if self.peek() == &Token::Symbol(',') {
                    self.next();
                } else {
                    break;
                }
            }
        }
        let close = self.column();
        self.expect(')', &format!("to close {name}(…)"))?;
        self.depth -= 1;
        if args.len() != params.len() {
            return Err(self.error(
                close,
                format!(
                    "{name} takes {} argument{}, given {}",
                    params.len(),
                    if params.len() == 1 { "" } else { "s" },
                    args.len()
                ),
            ));
        }
        Ok((Node::Call(f, args), result, column))
    }
}
