//! Linear constraints as text: `0 <= x - y < 2000 && y <= 10000`, `x1 + x2 - x4 == 0`,
//! `8*x2 - 3*x3 >= 0`, `true`. A conjunct is a chain of linear expressions joined by
//! `<`, `<=`, `==` (or `=`), `>=`, `>`; conjuncts are joined by `&&` (or `∧`). A
//! coefficient is an integer, a decimal (`2.5`) or a fraction (`5/2`).

use super::poly::{HalfSpace, Poly, Q};

/// A parse error: the message and the byte offset in the text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    /// What is wrong.
    pub message: String,
    /// Byte offset of the offending token.
    pub offset: usize,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(Q),
    Name(String),
    Plus,
    Minus,
    Star,
    Op(Op),
    And,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Lt,
    Le,
    Eq,
    Ge,
    Gt,
}

fn number(text: &str) -> Option<Q> {
    super::rat::parse(text)
}

fn lex(text: &str) -> Result<Vec<(Tok, usize)>, ParseError> {
    let mut out = Vec::new();
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let mut i = 0;
    while i < chars.len() {
        let (at, c) = chars[i];
        let next = chars.get(i + 1).map(|&(_, c)| c);
        let (tok, len) = match c {
            c if c.is_whitespace() => {
                i += 1;
                continue;
            }
            '+' => (Tok::Plus, 1),
            '-' | '−' => (Tok::Minus, 1),
            '*' => (Tok::Star, 1),
            '∧' => (Tok::And, 1),
            '&' if next == Some('&') => (Tok::And, 2),
            '<' if next == Some('=') => (Tok::Op(Op::Le), 2),
            '<' => (Tok::Op(Op::Lt), 1),
            '>' if next == Some('=') => (Tok::Op(Op::Ge), 2),
            '>' => (Tok::Op(Op::Gt), 1),
            '=' if next == Some('=') => (Tok::Op(Op::Eq), 2),
            '=' => (Tok::Op(Op::Eq), 1),
            '≤' => (Tok::Op(Op::Le), 1),
            '≥' => (Tok::Op(Op::Ge), 1),
            c if c.is_ascii_digit() => {
                let mut j = i;
                while j < chars.len()
                    && (chars[j].1.is_ascii_digit() || chars[j].1 == '.' || chars[j].1 == '/')
                {
                    j += 1;
                }
                let end = chars.get(j).map_or(text.len(), |&(o, _)| o);
                let q = number(&text[at..end]).ok_or_else(|| ParseError {
                    message: format!("`{}` is not a number", &text[at..end]),
                    offset: at,
                })?;
                out.push((Tok::Num(q), at));
                i = j;
                continue;
            }
            c if c.is_alphabetic() || c == '_' => {
                let mut j = i;
                while j < chars.len()
                    && (chars[j].1.is_alphanumeric() || chars[j].1 == '_' || chars[j].1 == '.')
                {
                    j += 1;
                }
                let end = chars.get(j).map_or(text.len(), |&(o, _)| o);
                out.push((Tok::Name(text[at..end].to_string()), at));
                i = j;
                continue;
            }
            other => {
                return Err(ParseError {
                    message: format!("unexpected `{other}`"),
                    offset: at,
                });
            }
        };
        out.push((tok, at));
        i += len;
    }
    Ok(out)
}

/// Parses a conjunction of linear constraints over the variables `names` (in order).
pub fn parse(text: &str, names: &[String]) -> Result<Poly, ParseError> {
    let toks = lex(text)?;
    let mut p = Poly::universe(names.len());
    let words: Vec<&str> = text.split_whitespace().collect();
    if words == ["true"] {
        return Ok(p);
    }
    if words == ["false"] {
        return Ok(Poly::empty(names.len()));
    }
    let mut pos = 0;
    loop {
        // A chain: expr (op expr)+
        let (mut left, mut at) = expr(&toks, &mut pos, names, text.len())?;
        let mut ops = 0;
        while let Some((Tok::Op(op), o)) = toks.get(pos) {
            let op = *op;
            let _ = o;
            pos += 1;
            let (right, next_at) = expr(&toks, &mut pos, names, text.len())?;
            // left op right  ⇔  (left − right) op 0
            let (a, c) = sub(&left, &right);
            add(&mut p, a, c, op);
            left = right;
            at = next_at;
            ops += 1;
        }
        if ops == 0 {
            return Err(ParseError {
                message: "expected a comparison (<, <=, ==, >=, >)".into(),
                offset: at,
            });
        }
        match toks.get(pos) {
            None => return Ok(p),
            Some((Tok::And, _)) => pos += 1,
            Some((_, o)) => {
                return Err(ParseError {
                    message: "expected `&&` between constraints".into(),
                    offset: *o,
                });
            }
        }
    }
}

/// A linear expression: coefficients and a constant.
type Lin = (Vec<Q>, Q);

fn sub(l: &Lin, r: &Lin) -> Lin {
    (
        l.0.iter().zip(&r.0).map(|(a, b)| a - b).collect(),
        l.1 - r.1,
    )
}

fn add(p: &mut Poly, a: Vec<Q>, c: Q, op: Op) {
    // a·x + c  op  0
    let b = -c;
    let neg: Vec<Q> = a.iter().map(|x| -x).collect();
    match op {
        Op::Le => p.add(HalfSpace::le(a, b)),
        Op::Lt => p.add(HalfSpace { a, b, strict: true }),
        Op::Ge => p.add(HalfSpace::le(neg, -b)),
        Op::Gt => p.add(HalfSpace {
            a: neg,
            b: -b,
            strict: true,
        }),
        Op::Eq => p.add_eq(a, b),
    }
}

fn expr(
    toks: &[(Tok, usize)],
    pos: &mut usize,
    names: &[String],
    end: usize,
) -> Result<(Lin, usize), ParseError> {
    let start = toks.get(*pos).map_or(end, |t| t.1);
    let mut lin: Lin = (vec![Q::zero(); names.len()], Q::zero());
    let mut sign = Q::one();
    let mut first = true;
    loop {
        match toks.get(*pos) {
            Some((Tok::Minus, _)) => {
                sign = -sign;
                *pos += 1;
                continue;
            }
            Some((Tok::Plus, _)) if first => {
                *pos += 1;
                continue;
            }
            _ => {}
        }
        let mut coef = sign;
        let mut var = None;
        match toks.get(*pos) {
            Some((Tok::Num(q), _)) => {
                coef *= q;
                *pos += 1;
                if let Some((Tok::Star, _)) = toks.get(*pos) {
                    *pos += 1;
                }
                if let Some((Tok::Name(n), o)) = toks.get(*pos) {
                    var = Some((n.clone(), *o));
                    *pos += 1;
                }
            }
            Some((Tok::Name(n), o)) => {
                var = Some((n.clone(), *o));
                *pos += 1;
            }
            other => {
                return Err(ParseError {
                    message: "expected a number or a clock".into(),
                    offset: other.map_or(end, |t| t.1),
                });
            }
        }
        match var {
            Some((n, o)) => {
                let k = names
                    .iter()
                    .position(|x| *x == n)
                    .ok_or_else(|| ParseError {
                        message: format!("unknown clock `{n}` (known: {})", names.join(", ")),
                        offset: o,
                    })?;
                lin.0[k] += coef;
            }
            None => lin.1 += coef,
        }
        first = false;
        sign = Q::one();
        match toks.get(*pos) {
            Some((Tok::Plus, _)) => *pos += 1,
            Some((Tok::Minus, _)) => {
                sign = -Q::one();
                *pos += 1;
            }
            _ => return Ok((lin, start)),
        }
    }
}
