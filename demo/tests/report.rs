//! Smoke test: a small run writes `index.html` and every PNG it references.

use std::path::PathBuf;
use std::time::{SystemTime, UNIX_EPOCH};

use mcg_demo::Config;

/// A fresh folder under the system temp dir, unique to this process and moment.
fn temp_out_dir() -> PathBuf {
    let nanos = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    std::env::temp_dir().join(format!("mcg-demo-smoke-{}-{nanos}", std::process::id()))
}

/// The `src="…"` attributes of a page, in order.
fn image_sources(html: &str) -> Vec<String> {
    html.split("src=\"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn report_writes_index_and_all_figures() {
    let out_dir = temp_out_dir();
    let config = Config {
        out_dir: out_dir.clone(),
        samples: 20_000,
        progress: false,
        ..Config::default()
    };
    let index = mcg_demo::run(&config).expect("report runs");

    assert!(index.is_absolute(), "{}", index.display());
    assert_eq!(index, out_dir.canonicalize().unwrap().join("index.html"));
    let html = std::fs::read_to_string(&index).expect("index.html is readable");
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    assert!(html.contains("von Mises-Fisher lobes"));

    let sources = image_sources(&html);
    assert!(
        sources.len() >= 4,
        "expected the vMF figures, found {sources:?}"
    );
    for src in &sources {
        assert!(
            !src.contains("..") && !src.starts_with('/'),
            "{src} is not a plain relative path"
        );
        let bytes = std::fs::read(out_dir.join(src)).unwrap_or_else(|e| panic!("{src}: {e}"));
        assert!(bytes.len() > 1000, "{src} is only {} bytes", bytes.len());
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{src} is not a PNG"
        );
    }

    std::fs::remove_dir_all(&out_dir).ok();
}
