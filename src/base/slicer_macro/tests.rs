//! The macro language's tests: each construct the makers' presets use,
//! the errors, and the bounds of hostile input.

use super::*;

fn vars() -> Vars {
    let mut v = Vars::new();
    let f = |x: f64| Value::Float(x);
    v.insert(
        "first_layer_temperature".into(),
        Value::List(vec![f(215.0), f(230.0)]),
    );
    v.insert(
        "first_layer_bed_temperature".into(),
        Value::List(vec![f(60.0)]),
    );
    v.insert("layer_height".into(), f(0.2));
    v.insert("max_layer_z".into(), f(10.4));
    v.insert("max_print_height".into(), f(210.0));
    v.insert("z_offset".into(), f(0.0));
    v.insert("initial_tool".into(), Value::Int(0));
    v.insert("has_wipe_tower".into(), Value::Bool(false));
    v.insert("printer_model".into(), Value::Str("MK3S".into()));
    v.insert(
        "filament_settings_id".into(),
        Value::List(vec![Value::Str("Prusament PA11 Carbon".into())]),
    );
    v.insert("park".into(), Value::Shown(12.3, "12.300".into()));
    v.insert("empty_list".into(), Value::List(vec![]));
    v.insert("e_retracted".into(), Value::List(vec![f(0.0), f(0.0)]));
    v.insert("retract_length".into(), Value::List(vec![f(0.8), f(0.7)]));
    v
}

fn x(t: &str) -> String {
    expand(t, &vars()).unwrap_or_else(|e| panic!("{t}: {e:?}"))
}

#[test]
fn legacy_and_braced_variables() {
    assert_eq!(x("M104 S[first_layer_temperature]"), "M104 S215");
    assert_eq!(x("M104 S[first_layer_temperature_1]"), "M104 S230");
    assert_eq!(
        x("M104 S[first_layer_temperature[initial_tool]]"),
        "M104 S215"
    );
    assert_eq!(x("M140 S{first_layer_bed_temperature[0]}"), "M140 S60");
    assert_eq!(x("M862.3 P \"[printer_model]\""), "M862.3 P \"MK3S\"");
    assert_eq!(x("[has_wipe_tower] {has_wipe_tower}"), "0 false");
    assert_eq!(x("G1 Z{park}"), "G1 Z12.300");
    assert_eq!(x("G1 Z{park + 1}"), "G1 Z13.3");
}

#[test]
fn arithmetic_and_functions() {
    assert_eq!(
        x("G1 Z{z_offset+min(max_layer_z+1, max_print_height)}"),
        "G1 Z11.4"
    );
    assert_eq!(x("{7/2} {7.0/2} {7%3} {-3/2}"), "3 3.5 1 -1");
    assert_eq!(
        x("{int(2.7)} {round(2.5)} {round(-2.5)} {max(1, 2)}"),
        "2 3 -3 2"
    );
    assert_eq!(
        x("{digits(3.14159, 6, 2)}|{zdigits(3.1, 6, 2)}"),
        "  3.14|003.10"
    );
    assert_eq!(x("{first_layer_temperature[0] * 2/3}"), "143.333");
    assert_eq!(
        x("{1000000.0} {0.0001} {1e-5} {0.1+0.2}"),
        "1e+06 0.0001 1e-05 0.3"
    );
    assert_eq!(x("{\"a\" + 1}"), "a1");
}

#[test]
fn conditions_and_matches() {
    let t = "{if filament_settings_id[initial_tool]=~/.*Prusament PA11.*/}\nA\n{elsif layer_height < 0.1}B{else}\nC\n{endif}\nD";
    assert_eq!(x(t), "\nA\n\nD");
    assert_eq!(
        x("M221 S{if layer_height<0.075}100{else}95{endif}"),
        "M221 S95"
    );
    assert_eq!(
        x("{if not has_wipe_tower and (layer_height > 0.1 or false)}y{endif}"),
        "y"
    );
    assert_eq!(x("{(layer_height > 0.1 ? 230 : 200)}"), "230");
    assert_eq!(x("{layer_height > 0.1 ? \"a\" : \"b\"}"), "a");
    assert_eq!(
        x("{if printer_model == \"MK3S\"}m{endif}{if printer_model != \"MK3S\"}n{endif}"),
        "m"
    );
    assert_eq!(x("{if printer_model !~ /MK.*/}m{else}k{endif}"), "k");
    assert_eq!(x("{if 1 <> 2 && 2 >= 2 || false}t{endif}"), "t");
}

#[test]
fn errors_name_the_line_and_the_variable() {
    let e = expand("G28\nM104 S{hot_end_temp}\n", &vars()).unwrap_err();
    assert_eq!(e.line, 2);
    assert!(e.message.contains("`hot_end_temp`"), "{e:?}");
    let e = expand("G28\n\nM104 S[bed_type]", &vars()).unwrap_err();
    assert_eq!(
        (e.line, e.column, e.message.as_str()),
        (3, 7, "unknown variable `bed_type` (column 7)")
    );
    for bad in [
        "{if layer_height}x{endif}",
        "{if true}x",
        "{else}",
        "{1 +}",
        "M117 [not a var]",
        "{layer_height + \"a\" * 2}",
        "{empty_list[0]}",
        "[empty_list]",
        "{1/0}",
        "{\"abc}",
    ] {
        assert!(expand(bad, &vars()).is_err(), "{bad}");
    }
    // an unknown variable in a branch not taken is still named
    let t = Template::parse("{if false}{bed_type}{endif}[printer_model]").unwrap();
    assert_eq!(t.expand(&vars()).unwrap(), "MK3S");
    let names: Vec<String> = t.variables().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["bed_type", "printer_model"]);
}

#[test]
fn hostile_nesting_is_refused() {
    let deep = format!("{{{}1{}}}", "(".repeat(10_000), ")".repeat(10_000));
    assert!(expand(&deep, &vars()).is_err());
    let ifs = "{if true}".repeat(10_000);
    assert!(expand(&ifs, &vars()).is_err());
}

#[test]
fn reals_print_like_ostream() {
    for (v, s) in [
        (215.0, "215"),
        (0.2, "0.2"),
        (1234567.0, "1.23457e+06"),
        (123456.0, "123456"),
        (0.000012345, "1.2345e-05"),
        (-3.5, "-3.5"),
        (2.0 / 3.0, "0.666667"),
        (999999.5, "1e+06"),
    ] {
        assert_eq!(fmt_g(v), s, "{v}");
    }
}

fn xv(t: &str, v: &Vars) -> String {
    expand(t, v).unwrap_or_else(|e| panic!("{t}: {e:?}"))
}

#[test]
fn inline_conditionals_anywhere() {
    // in the middle of a line, nested, and in code with `then`
    assert_eq!(
        x("M104 S{if layer_height > 0.1}{if true}2{endif}30{elsif false}1{else}0{endif} T0"),
        "M104 S230 T0"
    );
    assert_eq!(
        x("{if layer_height < 0.1 then \"fine\" elsif layer_height < 0.3 then \"normal\" else \"draft\" endif}"),
        "normal"
    );
    // statements before an `if`, and the ternary inside an expression
    assert_eq!(
        x("{local t = 1; if t > 0}pos{else}neg{endif}|{(t > 0 ? 1 : 2) + 10}"),
        "pos|11"
    );
    // a name that starts like a keyword is a name
    let e = expand("{elsif_temp}", &vars()).unwrap_err();
    assert!(e.message.contains("unknown variable `elsif_temp`"), "{e:?}");
}

#[test]
fn statements_local_global_and_vectors() {
    let t = "{local a = 3; global g = (1, 2.5, 3); a = a * 2; g[0] = 7}{a} {g[0]} {g[1]} {size(g)} {empty(g)}";
    assert_eq!(x(t), "6 7 2.5 3 false");
    assert_eq!(x("{local v = repeat(3, \"ab\"); v[1] + v[2]}"), "abab");
    assert_eq!(x("{local n = (1, 2); local m = n; m[1]}"), "2");
    assert_eq!(x("{local s = \"x\" + 1 + \"y\"}{s}"), "x1y");
    // a global outlives its expansion when the caller keeps the globals
    let mut globals = Vars::new();
    let a = Template::parse("{global used = 5}").unwrap();
    let b = Template::parse("M117 {used + 1}").unwrap();
    assert_eq!(a.globals(), ["used"]);
    a.expand_with(&vars(), &mut globals).unwrap();
    assert_eq!(b.expand_with(&vars(), &mut globals).unwrap(), "M117 6");
    // a local is not a slicer's setting to change, nor one to read later
    let e = expand("{layer_height = 2}", &vars()).unwrap_err();
    assert!(e.message.contains("cannot be assigned"), "{e:?}");
    let e = expand("{first_layer_temperature[0] = 2}", &vars()).unwrap_err();
    assert!(e.message.contains("cannot be assigned"), "{e:?}");
    // what a template makes itself is not an outside variable
    let t = Template::parse("{local k = 2}{k}[printer_model]").unwrap();
    let names: Vec<String> = t.variables().into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["printer_model"]);
}

#[test]
fn functions_of_the_current_bundles() {
    let mut v = vars();
    v.insert(
        "idle_temperature".into(),
        Value::List(vec![Value::Nil, Value::Int(170)]),
    );
    v.insert("extruded_weight_total".into(), Value::Float(500.0));
    assert_eq!(
        xv(
            "{is_nil(idle_temperature[0])} {is_nil(idle_temperature[1])}",
            &v
        ),
        "true false"
    );
    assert_eq!(
        xv("{one_of(printer_model, \"MINI\", /MK3.*/)} {one_of(printer_model, \"XL\")} {one_of(printer_model, ~\"M\" + \"K.S\")}", &v),
        "true false true"
    );
    assert_eq!(
        xv(
            "{interpolate_table(extruded_weight_total, (0,4000), (1000,1700), (10000,1700))}",
            &v
        ),
        "2850"
    );
    assert!(expand("{interpolate_table(20000, (0,1), (10,2))}", &v).is_err());
    assert!(expand("{interpolate_table(5, (10,1), (0,2))}", &v).is_err());
    assert_eq!(
        xv(
            "{digits(2.6, 4)}|{zdigits(-3, 4)}|{zdigits(7.25, 6, 1)}",
            &v
        ),
        "   3|-003|0007.2"
    );
    assert_eq!(
        xv("{min(2, 3.5)} {max(2, 3)} {int(-2.7)} {round(-2.5)}", &v),
        "2 3 -2 -3"
    );
    assert_eq!(
        xv("{first_layer_temperature[0] == 215.000000001}", &v),
        "true"
    );
    assert_eq!(xv("{\"5\" == 5} {printer_model < \"Z\"}", &v), "true true");
}

#[test]
fn random_is_seeded_by_the_template() {
    let t = "{random(1, 6)} {random(1, 6)} {random(1, 6)} {random(0.0, 1.0)}";
    let a = x(t);
    assert_eq!(a, x(t), "the same template, the same numbers");
    let parts: Vec<&str> = a.split(' ').collect();
    for p in &parts[..3] {
        let k: i64 = p.parse().unwrap();
        assert!((1..=6).contains(&k), "{a}");
    }
    let r: f64 = parts[3].parse().unwrap();
    assert!((0.0..1.0).contains(&r), "{a}");
    // every face turns up: uniform, not stuck
    let many = "{random(1, 6)}".repeat(200);
    let out = x(&many);
    for face in '1'..='6' {
        assert!(out.contains(face), "{face} missing in {out}");
    }
    assert!(expand("{random(3, 1)}", &vars()).is_err());
}

#[test]
fn errors_name_line_and_column() {
    let e = expand("G28\nM104 S{1 + }\n", &vars()).unwrap_err();
    assert_eq!((e.line, e.column), (2, 12), "{e:?}");
    let e = expand("G1\n  {if 3}x{endif}", &vars()).unwrap_err();
    assert_eq!((e.line, e.column), (2, 7), "{e:?}");
    assert!(e.message.contains("expected a boolean"), "{e:?}");
    let e = expand("é {nope}", &vars()).unwrap_err();
    assert_eq!((e.line, e.column), (1, 4), "{e:?}");
    assert!(e.message.contains("unknown variable `nope`"), "{e:?}");
}

#[test]
fn a_flat_chain_is_an_error_not_a_stack_overflow() {
    // 20,000 terms in one `{…}`: the tree's depth counts, not the text's
    // nesting (before, this parsed and its evaluation overflowed the stack)
    for op in ["+", "*", " and ", " == ", "-", "?1:"] {
        let chain = format!("{{1{}}}", format!("{op}1").repeat(20_000));
        let e = Template::parse(&chain).map(|_| ()).unwrap_err();
        assert!(e.message.contains("nested more than"), "{op}: {e:?}");
    }
    let nots = format!("{{{}true}}", "!".repeat(20_000));
    assert!(Template::parse(&nots).is_err());
    let ifs = format!("{}x{}", "{if true}".repeat(500), "{endif}".repeat(500));
    assert!(Template::parse(&ifs).is_err());
    // a deep but allowed template still expands
    let ok = format!("{{{}1{}}}", "(".repeat(50), ")".repeat(50));
    assert_eq!(x(&ok), "1");
}

#[test]
fn parsing_is_linear() {
    // 100,000 placeholders on 100,000 lines took 71 s when each error
    // position counted the lines from the start; now one pass
    let text = "G1 X[layer_height] Y{max_layer_z}\n".repeat(100_000);
    let t0 = std::time::Instant::now();
    let t = Template::parse(&text).unwrap();
    let out = t.expand(&vars()).unwrap();
    assert!(t0.elapsed().as_secs_f64() < 10.0, "{:?}", t0.elapsed());
    assert_eq!(out.lines().count(), 100_000);
    assert!(out.starts_with("G1 X0.2 Y10.4\n"));
    // as many different names, listed in one pass too
    let names: String = (0..100_000).map(|k| format!("[v{k}]\n")).collect();
    let t0 = std::time::Instant::now();
    let vs = Template::parse(&names).unwrap().variables();
    assert!(t0.elapsed().as_secs_f64() < 10.0, "{:?}", t0.elapsed());
    assert_eq!(vs.len(), 100_000);
    assert_eq!(vs[99_999], ("v99999".to_string(), 100_000));
    // an error at the end still names its line
    let bad = text.clone() + "{oops";
    assert_eq!(Template::parse(&bad).unwrap_err().line, 100_001);
}

#[test]
fn patterns_are_compiled_once_and_capped() {
    // one pattern, many uses: compiled once
    let same = "{if printer_model =~ /MK.*/}a{endif}".repeat(3000);
    let t = Template::parse(&same).unwrap();
    assert_eq!(t.patterns.len(), 1);
    assert_eq!(t.expand(&vars()).unwrap().len(), 3000);
    // 3,000 different ones: refused at the 65th, not 1.5 GB of automata
    let many: String = (0..3000)
        .map(|k| format!("{{if printer_model =~ /M{k}.*/}}a{{endif}}"))
        .collect();
    let e = Template::parse(&many).unwrap_err();
    assert!(
        e.message.contains("more than 64 different patterns"),
        "{e:?}"
    );
    // computed ones share the cap
    let computed: String = (0..100)
        .map(|k| format!("{{one_of(printer_model, ~\"X{k}\")}}"))
        .collect();
    let e = expand(&computed, &vars()).unwrap_err();
    assert!(e.message.contains("different patterns"), "{e:?}");
    // a pattern whose automaton is huge is refused by its size
    let e = Template::parse("{printer_model =~ /\\w{1000}\\w{1000}\\w{1000}/}").unwrap_err();
    assert!(e.message.contains("bad regular expression"), "{e:?}");
}

#[test]
fn output_values_and_work_are_bounded() {
    // doubling a string 40 times would be a terabyte
    let doubling = format!("{{local s = \"xx\"{}}}", "; s = s + s".repeat(40));
    let e = expand(&doubling, &vars()).unwrap_err();
    assert!(e.message.contains("longer than"), "{e:?}");
    let e = expand("{local v = repeat(1000000000, 1)}", &vars()).unwrap_err();
    assert!(e.message.contains("repeat"), "{e:?}");
    // copies of a big vector count as work
    let copies = format!(
        "{{local v = repeat(1000000, 1){}}}",
        "; local w = v".repeat(100)
    );
    let e = expand(&copies, &vars()).unwrap_err();
    assert!(e.message.contains("steps"), "{e:?}");
    // the output: a long text written many times by legacy names
    let mut v = vars();
    v.insert("big".into(), Value::Str("y".repeat(1 << 20)));
    let e = expand(&"[big]".repeat(8), &v).unwrap_err();
    assert!(e.message.contains("longer than"), "{e:?}");
}

/// An index past a vector's end reads its first element, as PrusaSlicer's
/// parser reads one (a template for five tools on a machine with two).
#[test]
fn an_index_past_the_end_reads_the_first_element() {
    assert_eq!(x("{first_layer_temperature[4]}"), "215");
    assert_eq!(
        x("[first_layer_temperature[3]] [first_layer_temperature_1]"),
        "215 230"
    );
    assert_eq!(
        x("{if first_layer_temperature[2] > 0 and false}M104 T2{endif}ok"),
        "ok"
    );
    assert_eq!(x("{local v = (1, 2); v[7]}"), "1");
    assert_eq!(x("{is_nil(first_layer_temperature[9])}"), "false");
}

/// The slicer's output vectors take a number per element, which the
/// caller reads back; they keep their size, and nothing else is writable.
#[test]
fn the_slicers_output_variables_are_assigned_and_read_back() {
    let t = Template::parse(
        "G1 E-{retract_length[0]}\n{e_retracted[0] = retract_length[0]}{e_retracted[0]} {e_retracted[1]}",
    )
    .unwrap();
    let (out, outputs) = t.expand_io(&vars(), &mut Vars::new()).unwrap();
    assert_eq!(out, "G1 E-0.8\n0.8 0");
    assert_eq!(
        outputs.get("e_retracted"),
        Some(&Value::List(vec![Value::Float(0.8), Value::Float(0.0)]))
    );
    // untouched, nothing comes back
    let t = Template::parse("{e_retracted[1]}").unwrap();
    assert!(t.expand_io(&vars(), &mut Vars::new()).unwrap().1.is_empty());
    for (bad, why) in [
        ("{e_retracted[2] = 1}", "has 2 elements, no index 2"),
        ("{e_retracted = 1}", "assign its elements"),
        ("{e_retracted[0] = \"a\"}", "takes a number"),
        ("{e_restart_extra[0] = 1}", "cannot be assigned"),
    ] {
        let e = expand(bad, &vars()).unwrap_err();
        assert!(e.message.contains(why), "{bad}: {e:?}");
    }
}
