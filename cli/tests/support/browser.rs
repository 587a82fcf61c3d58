//! Headless Chromium for the CLI tests (Debian's `chromium`, installed by
//! `tools/setup/setup_system.sh`): the DOM after scripts ran, screenshots, and
//! the console log. WebGL runs on SwiftShader (`--use-angle=swiftshader
//! --enable-unsafe-swiftshader`: the CPU rasteriser, no GPU needed; without
//! the opt-in flag Chromium falls back to it with a deprecation warning on
//! the console).

use std::path::Path;
use std::process::Command;

/// `file://` URL of `page` plus `fragment` (e.g. `#frame=3`, or empty).
pub fn file_url(page: &Path, fragment: &str) -> String {
    let abs = std::fs::canonicalize(page).unwrap_or_else(|_| page.to_path_buf());
    format!("file://{}{fragment}", abs.display())
}

/// Runs headless Chromium on `url` with its own profile directory and the
/// `extra` flags (`--dump-dom`, `--screenshot=…`, `--window-size=…`):
/// returns stdout (the DOM with `--dump-dom`) and stderr (the log, with a
/// `:CONSOLE` line per console message).
pub fn chromium(url: &str, profile: &Path, extra: &[&str]) -> (String, String) {
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--log-level=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium is not installed: run tools/setup/setup_system.sh");
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Console messages in a Chromium log, except SwiftShader's performance
/// notices (`GL Driver Message (OpenGL, Performance, …)`, e.g. "GPU stall
/// due to ReadPixels", which the driver emits when a page reads pixels
/// back; they are informational, not errors).
pub fn console_messages(log: &str) -> Vec<&str> {
    log.lines()
        .filter(|l| l.contains(":CONSOLE"))
        .filter(|l| !l.contains("GL Driver Message (OpenGL, Performance"))
        .collect()
}

/// The value of attribute `name` on the `<body>` element of a dumped DOM.
pub fn body_attr<'a>(dom: &'a str, name: &str) -> Option<&'a str> {
    let body = &dom[dom.find("<body")?..];
    let body = &body[..body.find('>')?];
    let key = format!("{name}=\"");
    let at = body.find(&key)? + key.len();
    Some(&body[at..at + body[at..].find('"')?])
}

/// RGBA pixels and size of a PNG screenshot.
pub fn png_pixels(path: &Path) -> (Vec<u8>, u32, u32) {
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut dec = png::Decoder::new(std::io::BufReader::new(f));
    dec.set_transformations(png::Transformations::EXPAND);
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (buf, info.width, info.height)
}
