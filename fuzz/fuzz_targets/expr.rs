//! Expression text → compile and evaluate at a few points.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3dp::base::expr::{eval_const, var, Expr, Memo, Params};

fuzz_target!(|data: &[u8]| {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let mut params = Params::new();
    params.insert("radius".into(), 30.0);
    params.insert("height".into(), 100.0);
    let _ = eval_const(src, &params);
    let all: Vec<usize> = (0..var::COUNT).collect();
    if let Ok(e) = Expr::compile(src, &params, &all) {
        for vars in [
            [0.0; var::COUNT],
            [1.0, -2.0, 3.5, 4.0, 0.5, 0.2, 40.0, 7.0, 100.0, 0.07, 0.25],
            [1e300, -1e300, f64::MIN_POSITIVE, 1e-300, 6.28, 1e9, 1e-9, 1e6, 1e6, 1.0, 0.999],
        ] {
            let _ = e.eval(&vars);
        }
    }
    if let Ok(e) = Expr::compile_ext(src, &params, &all, &["len", "depth"]) {
        let ext = vec![0.5; 2 + e.rands()];
        let _ = e.eval_ext(&[1.0; var::COUNT], &ext, &mut Memo::default());
    }
});
