//! `with:` values: what a template use (or a whole recipe included as a
//! part) gives the params of what it uses, evaluated where the use is
//! written. A param keeps its kind: a number (any expression over the
//! caller's params), `true`/`false`, a list, or one of a choice's strings
//! (written bare, `star`, or quoted, `'star'`; or the name of a choice param
//! of the caller whose string is one of them).

use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Kind, Params};
use crate::recipe::params::check_choices;
use crate::recipe::schema::{Num, RawChoice, RawParam};

/// A value a use gives one param, of that param's kind.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Given {
    /// A number.
    Num(f64),
    /// True or false.
    Bool(bool),
    /// A list of numbers.
    List(Vec<f64>),
    /// One of the choice's strings.
    Choice(String),
}

impl Given {
    /// The value as `--set` writes it: what [`crate::recipe::params::eval_params`]
    /// reads back to the same value (a number in Rust's shortest exact form).
    pub(crate) fn text(&self) -> String {
        match self {
            Given::Num(v) => format!("{v}"),
            Given::Bool(b) => b.to_string(),
            Given::List(v) => {
                let items: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
                format!("[{}]", items.join(", "))
            }
            Given::Choice(s) => s.clone(),
        }
    }
}

/// `given` (written at `place`) for the param `target`, evaluated in the
/// caller's `caller` params.
pub(crate) fn value(
    given: &RawParam,
    target: &RawParam,
    caller: &Params,
    place: &str,
) -> Result<Given> {
    let eval = |n: &Num| -> Result<f64> {
        let v = crate::recipe::eval::eval(n, caller, place)?;
        crate::recipe::eval::finite(v, place)
    };
    match (target, given) {
        (RawParam::Choice(c), RawParam::Num(Num::Expr(s))) => choice(c, s, caller, place),
        (RawParam::Choice(c), _) => Err(Error::input(
            place,
            format!("expected one of the choices {}", c.choices.join(", ")),
        )),
        (RawParam::List(_) | RawParam::Each(_), RawParam::List(items)) => items
            .iter()
            .enumerate()
            .map(|(k, n)| {
                let at = format!("{place}[{k}]");
                crate::recipe::eval::eval(n, caller, &at)
                    .and_then(|v| crate::recipe::eval::finite(v, &at))
            })
            .collect::<Result<Vec<f64>>>()
            .map(Given::List),
        (RawParam::List(_) | RawParam::Each(_), RawParam::Num(Num::Expr(s))) => {
            match caller.list(s.trim()) {
                Some(v) => Ok(Given::List(v.to_vec())),
                None => Err(Error::input(
                    place,
                    format!("`{s}` is not a list; expected [a, b, …] or the name of a list param"),
                )),
            }
        }
        (RawParam::List(_) | RawParam::Each(_), _) => {
            Err(Error::input(place, "expected a list [a, b, …]"))
        }
        (RawParam::Bool(_), RawParam::Bool(b)) => Ok(Given::Bool(*b)),
        (RawParam::Bool(_), RawParam::Num(n)) => {
            // a caller's true/false param passed on: 1 or 0
            let v = eval(n)?;
            if v == 1.0 || v == 0.0 {
                Ok(Given::Bool(v == 1.0))
            } else {
                Err(Error::input(
                    place,
                    format!("{v} is not allowed for a true/false param; expected true or false"),
                ))
            }
        }
        (RawParam::Bool(_), _) => Err(Error::input(place, "expected true or false")),
        (RawParam::Num(_), RawParam::Num(n)) => eval(n).map(Given::Num),
        (RawParam::Num(_), RawParam::Bool(b)) => Ok(Given::Num(if *b { 1.0 } else { 0.0 })),
        (RawParam::Num(_), _) => Err(Error::input(
            place,
            "expected a number or an expression string",
        )),
    }
}

/// The string of choice `c` that `s` names: bare or quoted, or a choice
/// param of the caller's whose string is one of `c`'s.
fn choice(c: &RawChoice, s: &str, caller: &Params, place: &str) -> Result<Given> {
    let bare = s.trim().trim_matches(|ch| ch == '\'' || ch == '"');
    if c.choices.iter().any(|x| x == bare) {
        return Ok(Given::Choice(bare.to_string()));
    }
    if let Some(Kind::Choice(x)) = caller.kind(bare) {
        if c.choices.contains(x) {
            return Ok(Given::Choice(x.clone()));
        }
    }
    Err(Error::input(
        place,
        format!(
            "`{bare}` is not a choice here; expected one of {}",
            c.choices.join(", ")
        ),
    ))
}

/// A template's params over `base` (the params its body sees besides its
/// own), in order: each from `given` when the use gives it, else its
/// default evaluated over the params before it. `def_place(name)` is where
/// a default is written; `named` reports a bad param name.
pub(crate) fn template_params(
    base: &Params,
    raw: &IndexMap<String, RawParam>,
    given: &IndexMap<String, Given>,
    def_place: &dyn Fn(&str) -> String,
) -> Result<Params> {
    let mut params = base.clone();
    // the template's choice strings join the ones expressions already know
    let mut strings: Vec<String> = params.symbols().map(str::to_string).collect();
    for (name, value) in raw {
        if let RawParam::Choice(c) = value {
            check_choices(c, &def_place(name))?;
            strings.extend(c.choices.iter().cloned());
        }
    }
    params.set_symbols(strings.iter().map(String::as_str));
    for (name, value) in raw {
        let place = def_place(name);
        let mine = given.get(name);
        match value {
            RawParam::Num(n) => {
                let v = match mine {
                    Some(Given::Num(v)) => *v,
                    _ => crate::recipe::eval::eval(n, &params, &place)
                        .and_then(|v| crate::recipe::eval::finite(v, &place))?,
                };
                params.insert(name.clone(), v);
            }
            RawParam::Bool(b) => {
                let b = match mine {
                    Some(Given::Bool(g)) => *g,
                    _ => *b,
                };
                params.insert(name.clone(), if b { 1.0 } else { 0.0 });
                params.set_kind(name, Kind::Bool(b));
            }
            RawParam::List(items) => {
                let v = match mine {
                    Some(Given::List(v)) => v.clone(),
                    _ => items
                        .iter()
                        .enumerate()
                        .map(|(k, n)| {
                            let at = format!("{place}[{k}]");
                            crate::recipe::eval::eval(n, &params, &at)
                                .and_then(|v| crate::recipe::eval::finite(v, &at))
                        })
                        .collect::<Result<Vec<f64>>>()?,
                };
                params.insert_list(name, v);
            }
            RawParam::Each(e) => {
                let v = match mine {
                    Some(Given::List(v)) => v.clone(),
                    _ => crate::recipe::params::each(e, &params, &place)?,
                };
                params.insert_list(name, v);
            }
            RawParam::Choice(c) => {
                let s = match mine {
                    Some(Given::Choice(s)) => s.clone(),
                    _ => c.default.clone(),
                };
                let v = params.symbol(&s).expect("the choices were declared");
                params.insert(name.clone(), v);
                params.set_kind(name, Kind::Choice(s));
            }
        }
        if expr::is_reserved(name) {
            return Err(Error::input(
                place,
                format!("`{name}` is a name expressions already use; choose another param name"),
            ));
        }
    }
    Ok(params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    fn raw(yaml: &str) -> IndexMap<String, RawParam> {
        parse_yaml(yaml, "t").unwrap()
    }

    #[test]
    fn values_keep_the_kind_of_the_param() {
        let target = raw("n: 1\nb: false\nl: [1]\nc: {choices: [round, star], default: round}\n");
        let mut caller = Params::new();
        caller.insert("k".into(), 3.0);
        caller.insert_list("ls", vec![4.0, 5.0]);
        let given = raw("n: \"2*k\"\nb: true\nl: [\"k\", 2]\nc: star\n");
        let v = |name: &str| value(&given[name], &target[name], &caller, name);
        assert_eq!(v("n").unwrap(), Given::Num(6.0));
        assert_eq!(v("b").unwrap(), Given::Bool(true));
        assert_eq!(v("l").unwrap(), Given::List(vec![3.0, 2.0]));
        assert_eq!(v("c").unwrap(), Given::Choice("star".into()));
        assert_eq!(Given::List(vec![3.0, 0.1]).text(), "[3, 0.1]");
        // a list param's name passes the list; a quoted choice is the choice
        let given = raw("l: ls\nc: \"'round'\"\n");
        assert_eq!(
            v2(&given, &target, &caller, "l"),
            Given::List(vec![4.0, 5.0])
        );
        assert_eq!(
            v2(&given, &target, &caller, "c"),
            Given::Choice("round".into())
        );
        // wrong kinds and strings are refused, naming what is allowed
        let bad = raw("c: square\nb: 2\nl: 3\n");
        let e = value(&bad["c"], &target["c"], &caller, "with.c").unwrap_err();
        assert!(e.message.contains("expected one of round, star"), "{e}");
        assert!(value(&bad["b"], &target["b"], &caller, "with.b").is_err());
        assert!(value(&bad["l"], &target["l"], &caller, "with.l").is_err());
    }

    fn v2(
        given: &IndexMap<String, RawParam>,
        target: &IndexMap<String, RawParam>,
        caller: &Params,
        name: &str,
    ) -> Given {
        value(&given[name], &target[name], caller, name).unwrap()
    }

    #[test]
    fn a_template_evaluates_its_params_in_order_with_the_given_ones() {
        let tpl = raw("size: 10\nd: \"2*size\"\nshape: {choices: [round, star], default: round}\nm: \"if(shape == 'star', 1, 0)\"\n");
        let mut given = IndexMap::new();
        given.insert("size".to_string(), Given::Num(3.0));
        given.insert("shape".to_string(), Given::Choice("star".into()));
        let p = template_params(&Params::new(), &tpl, &given, &|n| format!("t.{n}")).unwrap();
        assert_eq!(p["d"], 6.0);
        assert_eq!(p["m"], 1.0);
        assert_eq!(p.show("shape").as_deref(), Some("star"));
        let p =
            template_params(&Params::new(), &tpl, &IndexMap::new(), &|n| n.to_string()).unwrap();
        assert_eq!((p["d"], p["m"]), (20.0, 0.0));
    }
}
