//! docs/adding-an-effect.md shows the plastic_adhesion law and its test word for word: the
//! example on the page is the file that is compiled and tested.

use std::path::Path;

fn blocks(md: &str) -> Vec<String> {
    let mut out = vec![];
    let mut cur: Option<String> = None;
    for line in md.lines() {
        match (&mut cur, line.trim_start().starts_with("```")) {
            (None, true) if line.trim() == "```rust" => cur = Some(String::new()),
            (Some(_), true) => out.push(cur.take().unwrap()),
            (Some(b), false) => {
                b.push_str(line);
                b.push('\n');
            }
            _ => {}
        }
    }
    out
}

#[test]
fn the_page_shows_the_compiled_law_and_its_test() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let md = std::fs::read_to_string(root.join("docs/adding-an-effect.md")).unwrap();
    let shown = blocks(&md);
    for file in [
        "kernel/src/contact/laws/plastic_adhesion.rs",
        "tests/tests/plastic_adhesion.rs",
    ] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(
            shown.contains(&text),
            "docs/adding-an-effect.md does not show {file} as it is"
        );
    }
    // And the registry line it describes is there.
    let registry = std::fs::read_to_string(root.join("kernel/src/contact/laws/mod.rs")).unwrap();
    assert!(registry.contains("        plastic_adhesion: PlasticAdhesion,\n"));
}
