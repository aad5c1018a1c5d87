//! Compile-fail tests: each file under `compile_fail/` is a small program whose kernel
//! uses one construct outside the Cohort subset (or breaks one of its rules); the
//! expected diagnostic, with its span, is locked in the `.stderr` file next to it.
//! Regenerate with `TRYBUILD=overwrite cargo test -p cohort-tests --test compile_fail`.

#[test]
fn rejected_constructs() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/compile_fail/*.rs");
}
