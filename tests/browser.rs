//! The HTML reports in a real browser: headless Chromium opens the files that
//! `igemu render --html` and `igemu sweep --html` write and checks that every image decodes
//! (complete, natural width and height > 0), that no request leaves the file (every request
//! is the file itself or a `data:` URI), that no console error, log error or uncaught
//! exception occurs, that the sweep table sorts, and that a colour render's page shows its
//! images in colour with the CIEDE2000 heat map; it saves a screenshot of each page as a
//! test artefact (`target/tmp/browser/*.png`, `target/tmp/browser-colour/*.png`).
//!
//! Chromium is found at `IGEMU_CHROMIUM`, else `/usr/bin/chromium` or on `PATH`. Without
//! it the test prints a loud SKIP line and passes, unless `IGEMU_REQUIRE_BROWSER=1` (set by
//! `.ci/run`, which installs Debian's `chromium`): then it fails.

use headless_chrome::protocol::cdp::types::Event;
use headless_chrome::protocol::cdp::{Network, Page, Runtime};
use headless_chrome::{Browser, LaunchOptions, Tab};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::Duration;

const REQUIRE: &str = "IGEMU_REQUIRE_BROWSER";

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("IGEMU_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    let dirs = std::iter::once(PathBuf::from("/usr/bin")).chain(std::env::split_paths(&path));
    for d in dirs {
        for name in ["chromium", "chromium-browser", "google-chrome"] {
            let p = d.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

fn igemu(args: &[&str], dir: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("igemu runs");
    assert!(
        out.status.success(),
        "igemu {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// What the browser saw of one page.
#[derive(Default)]
struct Seen {
    requests: Vec<String>,
    problems: Vec<String>,
}

fn listen(tab: &Tab) -> Arc<Mutex<Seen>> {
    let seen = Arc::new(Mutex::new(Seen::default()));
    let s = seen.clone();
    tab.add_event_listener(Arc::new(move |e: &Event| {
        let mut s = s.lock().unwrap_or_else(|e| e.into_inner());
        match e {
            Event::NetworkRequestWillBeSent(r) => s.requests.push(r.params.request.url.clone()),
            Event::RuntimeConsoleAPICalled(c) => {
                use Runtime::ConsoleAPICalledEventTypeOption as T;
                if matches!(c.params.Type, T::Error | T::Assert | T::Warning) {
                    let args: Vec<String> = c
                        .params
                        .args
                        .iter()
                        .map(|a| format!("{:?}", a.value))
                        .collect();
                    s.problems
                        .push(format!("console {:?}: {}", c.params.Type, args.join(" ")));
                }
            }
            Event::RuntimeExceptionThrown(x) => s
                .problems
                .push(format!("exception: {}", x.params.exception_details.text)),
            Event::LogEntryAdded(l) => {
                use headless_chrome::protocol::cdp::Log::LogEntryLevel;
                if matches!(
                    l.params.entry.level,
                    LogEntryLevel::Error | LogEntryLevel::Warning
                ) {
                    s.problems.push(format!(
                        "log {:?} ({:?}): {} {}",
                        l.params.entry.level,
                        l.params.entry.source,
                        l.params.entry.text,
                        l.params.entry.url.clone().unwrap_or_default()
                    ));
                }
            }
            _ => {}
        }
    }))
    .expect("listener");
    seen
}

fn eval(tab: &Tab, js: &str) -> serde_json::Value {
    tab.evaluate(js, false)
        .unwrap_or_else(|e| panic!("evaluate {js}: {e}"))
        .value
        .unwrap_or(serde_json::Value::Null)
}

/// Opens `file` and checks it (module doc); returns the tab for page-specific checks.
fn open_and_check(browser: &Browser, file: &Path, images: usize, shot: &Path) -> Arc<Tab> {
    let tab = browser.new_tab().expect("tab");
    tab.set_default_timeout(Duration::from_secs(60));
    let seen = listen(&tab);
    tab.call_method(Network::Enable {
        max_total_buffer_size: None,
        max_resource_buffer_size: None,
        max_post_data_size: None,
        report_direct_socket_traffic: None,
        enable_durable_messages: None,
    })
    .expect("network events");
    tab.enable_log().expect("log events");
    tab.enable_runtime().expect("runtime events");
    let url = format!("file://{}", file.display());
    tab.navigate_to(&url)
        .and_then(|t| t.wait_until_navigated())
        .unwrap_or_else(|e| panic!("{url}: {e}"));
    // Let every image finish decoding.
    eval(
        &tab,
        "Promise.all(Array.from(document.images).map(i => i.decode().catch(() => null))).then(() => 1)",
    );
    let (requests, problems) = {
        let s = seen.lock().unwrap_or_else(|e| e.into_inner());
        (s.requests.clone(), s.problems.clone())
    };
    for r in &requests {
        assert!(
            r == &url || r.starts_with("data:"),
            "{}: a request left the file: {r}",
            file.display()
        );
    }
    assert!(problems.is_empty(), "{}: {problems:#?}", file.display());
    let v = eval(
        &tab,
        "JSON.stringify(Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth, i.naturalHeight, i.src.slice(0, 22)]))",
    );
    let imgs: Vec<(String, bool, u64, u64, String)> =
        serde_json::from_str(v.as_str().expect("a JSON string")).expect("image list");
    assert!(
        imgs.len() == images,
        "{}: {} images, expected {images}",
        file.display(),
        imgs.len()
    );
    for (alt, complete, w, h, src) in &imgs {
        assert!(
            *complete && *w > 0 && *h > 0,
            "{}: image `{alt}` did not decode (complete {complete}, natural {w}x{h})",
            file.display()
        );
        assert!(
            src.starts_with("data:image/"),
            "image `{alt}` is not inline: {src}"
        );
    }
    let png = tab
        .capture_screenshot(Page::CaptureScreenshotFormatOption::Png, None, None, true)
        .expect("screenshot");
    std::fs::write(shot, png).expect("screenshot written");
    eprintln!(
        "browser: {}: {} images decoded; screenshot {}",
        file.display(),
        imgs.len(),
        shot.display()
    );
    tab
}

/// Chromium, or `None` after a loud SKIP line (a failure under `IGEMU_REQUIRE_BROWSER=1`).
fn chromium_or_skip(test: &str) -> Option<PathBuf> {
    let chrome = chromium();
    if chrome.is_none() {
        let line = format!(
            "SKIP tests/browser.rs {test}: Chromium not installed (apt-get install chromium, or set IGEMU_CHROMIUM): the HTML reports were NOT opened in a browser"
        );
        if std::env::var(REQUIRE).is_ok_and(|v| v == "1") {
            panic!("{line}; {REQUIRE}=1 requires it");
        }
        eprintln!("\n*** {line} ***\n");
    }
    chrome
}

/// An empty folder `name` for a test's files.
fn fresh_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Headless Chromium with its profile in `dir`.
fn launch(chrome: PathBuf, dir: &Path) -> Browser {
    // Background services off: the machine may have no network, and none is needed.
    let args: Vec<&OsStr> = [
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
    ]
    .iter()
    .map(OsStr::new)
    .collect();
    Browser::new(
        LaunchOptions::default_builder()
            .path(Some(chrome))
            .headless(true)
            .sandbox(false)
            .window_size(Some((1400, 2400)))
            .user_data_dir(Some(dir.join("profile")))
            .args(args)
            .idle_browser_timeout(Duration::from_secs(120))
            .build()
            .expect("launch options"),
    )
    .expect("Chromium starts")
}

#[test]
fn html_reports_open_in_a_browser_without_errors() {
    let Some(chrome) = chromium_or_skip("html_reports_open_in_a_browser_without_errors") else {
        return;
    };
    let dir = fresh_dir("browser");
    let truth = ["--dof-truth", "--lens-samples", "8"];
    igemu(
        &[&["render", "-o", "r.png", "--html", "r.html"][..], &truth].concat(),
        &dir,
    );
    igemu(
        &[
            "render",
            "default-pinhole",
            "--hw",
            "log8-logadd",
            "-o",
            "l.png",
            "--html",
            "l.html",
        ],
        &dir,
    );
    let grid = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/grid.toml");
    igemu(
        &[
            "sweep",
            "--grid",
            grid.to_str().unwrap(),
            "--out",
            "s.jsonl",
            "--html",
            "s.html",
        ],
        &dir,
    );
    let browser = launch(chrome, &dir);

    // The render: 4 pictures (fixed, reference, difference, banding), the truth and the
    // difference to it, the layer map of the thin-lens default scene, and 5 plots (LUT,
    // histogram, the timelines of both depth-of-field schedules, sigma).
    let tab = open_and_check(&browser, &dir.join("r.html"), 12, &dir.join("render.png"));
    let links = eval(
        &tab,
        "JSON.stringify(Array.from(document.querySelectorAll('a[href^=\"#signals-\"]')).map(a => !!document.getElementById(a.getAttribute('href').slice(1))))",
    );
    let links: Vec<bool> = serde_json::from_str(links.as_str().unwrap()).unwrap();
    assert!(
        links.len() >= 6 && links.iter().all(|&b| b),
        "stage links: {links:?}"
    );

    readable_render_page(&tab, true);

    // A log-coded pinhole render: no depth of field (no layer map, no sigma plot).
    let tab = open_and_check(
        &browser,
        &dir.join("l.html"),
        7,
        &dir.join("render-log.png"),
    );
    readable_render_page(&tab, false);

    // The sweep: the Pareto plot; the table sorts numerically on a click.
    let tab = open_and_check(&browser, &dir.join("s.html"), 1, &dir.join("sweep.png"));
    let col = "Array.from(document.querySelectorAll('#rows-table thead th')).findIndex(t => t.textContent === 'mean Weber')";
    let sorted = |dir: i32| {
        let js = format!(
            "(() => {{ const c = {col}; document.querySelectorAll('#rows-table thead th')[c].click(); \
             const v = Array.from(document.querySelectorAll('#rows-table tbody tr')).map(r => parseFloat(r.cells[c].getAttribute('data-key'))); \
             return JSON.stringify(v); }})()"
        );
        let v: Vec<f64> = serde_json::from_str(eval(&tab, &js).as_str().unwrap()).unwrap();
        assert_eq!(v.len(), 48, "every row of examples/grid.toml");
        assert!(
            v.windows(2).all(|w| (w[1] - w[0]) * dir as f64 >= 0.0),
            "sorted {dir}: {v:?}"
        );
    };
    sorted(1);
    sorted(-1);
    let front = eval(
        &tab,
        "document.querySelectorAll('#rows-table tr.front').length",
    );
    assert!(front.as_u64().unwrap_or(0) >= 1, "the front is highlighted");
    sweep_page_fits(&tab);
}

/// The text of every `[label, ...]` array a script returns as a JSON string.
fn eval_json<T: serde::de::DeserializeOwned>(tab: &Tab, js: &str) -> T {
    let v = eval(tab, js);
    serde_json::from_str(
        v.as_str()
            .unwrap_or_else(|| panic!("{js}: not a JSON string: {v}")),
    )
    .unwrap_or_else(|e| panic!("{js}: {e}"))
}

/// Issue 30's readability of a render page: every signal row has values or says why not;
/// the banding map has its legend (and says when no contour was found); the gamma plot's
/// legend is under the figure, not drawn over the curves; with the truth, the algorithm /
/// quantisation split table.
fn readable_render_page(tab: &Tab, truth: bool) {
    // [signal, values, seen] of every signal row.
    let rows: Vec<(String, String, String)> = eval_json(
        tab,
        "JSON.stringify(Array.from(document.querySelectorAll('h3[id^=\"signals-\"] + table tr')).filter(r => r.cells[0].tagName === 'TD').map(r => [r.cells[0].textContent, r.cells[3].textContent, r.cells[4].textContent]))",
    );
    assert!(rows.len() >= 8, "signal rows: {rows:?}");
    for (name, values, seen) in &rows {
        let has_values = values.parse::<u64>().is_ok_and(|n| n > 0) && seen.contains("..");
        let says_why = seen.starts_with("not recorded") || seen.starts_with("none:");
        assert!(
            has_values || says_why,
            "signal {name}: values {values}, seen {seen}"
        );
    }
    for name in ["raster.clamped", "visibility.z"] {
        let r = rows
            .iter()
            .find(|r| r.0 == name)
            .unwrap_or_else(|| panic!("{name}: {rows:?}"));
        assert!(r.2.starts_with("not recorded"), "{r:?}");
    }
    // The banding map's legend and caption.
    let (legend, caption): (Vec<String>, String) = eval_json(
        tab,
        "(() => { const f = Array.from(document.querySelectorAll('figure')).find(f => f.querySelector('img[alt=\"banding map\"]')); return JSON.stringify([Array.from(f.querySelectorAll('.legend span')).map(s => s.textContent), f.querySelector('figcaption').textContent]); })()",
    );
    assert_eq!(legend.len(), 3, "banding legend: {legend:?}");
    assert!(
        legend.iter().any(|l| l.contains("smooth region")),
        "{legend:?}"
    );
    assert!(
        caption.contains("0 visible contour steps found")
            || caption.contains("beside a visible contour step"),
        "banding caption: {caption}"
    );
    // The gamma LUT plot: its legend keys under the figure, no legend text inside the SVG.
    let (keys, svg): (Vec<String>, String) = eval_json(
        tab,
        "(() => { const f = Array.from(document.querySelectorAll('figure')).find(f => f.querySelector('img[alt=\"gamma LUT transfer\"]')); return JSON.stringify([Array.from(f.querySelectorAll('.legend span')).map(s => s.textContent), atob(f.querySelector('img').src.split(',')[1])]); })()",
    );
    assert!(keys.len() >= 2, "LUT legend keys: {keys:?}");
    assert!(svg.contains("<svg"), "the LUT plot decodes as SVG");
    for k in &keys {
        assert!(
            !svg.contains(k.as_str()),
            "the LUT plot draws its legend `{k}` over the curves"
        );
    }
    // The depth-of-field truth's split table.
    let split: Vec<Vec<String>> = eval_json(
        tab,
        "JSON.stringify(Array.from(document.querySelectorAll('#truth-split tr')).map(r => Array.from(r.cells).map(c => c.textContent)))",
    );
    if truth {
        assert_eq!(
            split.len(),
            4,
            "header + total, algorithm, quantisation: {split:?}"
        );
        for (row, part) in split[1..]
            .iter()
            .zip(["total", "algorithm", "quantisation"])
        {
            assert!(row[0].starts_with(part) && row.len() == 4, "{row:?}");
            assert!(row[1..].iter().all(|c| c.contains(" / ")), "{row:?}");
        }
    } else {
        assert!(split.is_empty(), "no truth, no split table: {split:?}");
    }
}

/// The sweep page at a 1400-px window: the page does not scroll sideways (the table scrolls
/// inside its own box, whose last column can be scrolled into view), the plot fits, and
/// every highlighted front row's index labels a point of the Pareto plot.
fn sweep_page_fits(tab: &Tab) {
    let (inner, page_w, box_right, last_right, plot_w): (f64, f64, f64, f64, f64) = eval_json(
        tab,
        "(() => { const b = document.getElementById('rows-scroll'); b.scrollLeft = b.scrollWidth; \
         const ths = document.querySelectorAll('#rows-table thead th'); \
         const r = JSON.stringify([window.innerWidth, document.documentElement.scrollWidth, b.getBoundingClientRect().right, ths[ths.length - 1].getBoundingClientRect().right, document.images[0].getBoundingClientRect().width]); \
         b.scrollLeft = 0; return r; })()",
    );
    assert!(inner <= 1400.0, "window {inner}");
    assert!(
        page_w <= inner,
        "the page scrolls sideways: {page_w} > {inner}"
    );
    assert!(
        box_right <= inner,
        "the table's box ends at {box_right} > {inner}"
    );
    assert!(
        last_right <= box_right + 1.0,
        "the last column ends at {last_right}, past its box {box_right}"
    );
    assert!(plot_w <= inner, "the plot is {plot_w} px wide");
    let (indices, svg): (Vec<String>, String) = eval_json(
        tab,
        "(() => { const c = Array.from(document.querySelectorAll('#rows-table thead th')).findIndex(t => t.textContent === 'index'); \
         return JSON.stringify([Array.from(document.querySelectorAll('#rows-table tr.front')).map(r => r.cells[c].textContent), atob(document.images[0].src.split(',')[1]).replace(/\\s*\\n\\s*/g, '')]); })()",
    );
    assert!(!indices.is_empty());
    for i in &indices {
        assert!(
            svg.contains(&format!(">#{i}<")),
            "front row {i} is not labelled in the plot"
        );
    }
}

/// A colour render's page in the browser: the fixed and float images in RGB (the fixed one
/// not grey), a difference map per channel, the CIEDE2000 heat map (not all black) with its
/// four-stop legend, and one line per channel.
#[test]
fn a_colour_render_opens_in_colour_with_its_delta_e_map() {
    let Some(chrome) = chromium_or_skip("a_colour_render_opens_in_colour_with_its_delta_e_map")
    else {
        return;
    };
    let dir = fresh_dir("browser-colour");
    // The embedded default-colour scene at a quarter of its size.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/scene/default-colour.toml");
    let text = std::fs::read_to_string(scene).expect("the scene file");
    let small =
        text.replacen("width = 640", "width = 160", 1)
            .replacen("height = 480", "height = 120", 1);
    assert!(small.contains("width = 160") && small.contains("height = 120"));
    std::fs::write(dir.join("colour.toml"), small).unwrap();
    igemu(
        &["render", "colour.toml", "-o", "c.png", "--html", "c.html"],
        &dir,
    );
    let browser = launch(chrome, &dir);
    // 7 pictures (fixed and reference in RGB, a difference per channel, the banding map, the
    // layer map), the CIEDE2000 heat map and 5 plots (the timelines of both depth-of-field
    // schedules among them).
    let tab = open_and_check(
        &browser,
        &dir.join("c.html"),
        13,
        &dir.join("render-colour.png"),
    );
    let js = r#"(() => {
        const img = alt => Array.from(document.images).find(i => i.alt === alt);
        const pixels = alt => {
            const i = img(alt), c = document.createElement('canvas');
            c.width = i.naturalWidth; c.height = i.naturalHeight;
            const x = c.getContext('2d');
            x.drawImage(i, 0, 0);
            return x.getImageData(0, 0, c.width, c.height).data;
        };
        const count = (d, f) => { let n = 0; for (let k = 0; k < d.length; k += 4) if (f(d[k], d[k + 1], d[k + 2])) n++; return n; };
        return JSON.stringify({
            section: !!document.getElementById('colour'),
            alts: Array.from(document.images).map(i => i.alt),
            not_grey: count(pixels('fixed pipeline'), (r, g, b) => r !== g || g !== b),
            heat_lit: count(pixels('CIEDE2000 heat map'), (r, g, b) => r + g + b > 0),
            legend: Array.from(img('CIEDE2000 heat map').closest('figure').querySelectorAll('.legend span')).map(s => s.textContent),
            channels: document.querySelectorAll('#colour-channels tr').length - 1,
        });
    })()"#;
    let v: serde_json::Value =
        serde_json::from_str(eval(&tab, js).as_str().expect("a JSON string")).unwrap();
    eprintln!("browser: colour page: {v}");
    assert_eq!(v["section"], true, "{v}");
    for alt in [
        "fixed pipeline",
        "float reference",
        "difference, channel R",
        "difference, channel G",
        "difference, channel B",
        "CIEDE2000 heat map",
    ] {
        assert!(
            v["alts"].as_array().unwrap().iter().any(|a| a == alt),
            "no image `{alt}`: {v}"
        );
    }
    assert!(
        v["not_grey"].as_u64().unwrap() > 0,
        "the fixed image is grey: {v}"
    );
    assert!(
        v["heat_lit"].as_u64().unwrap() > 0,
        "the heat map is all black: {v}"
    );
    assert_eq!(
        v["legend"],
        serde_json::json!(["0", "1", "2.3: the JND", "5 and above"]),
        "{v}"
    );
    assert_eq!(v["channels"], 3, "{v}");
}

/// `igemu sequence --html`: the frames as an animated PNG (decoded by the browser as an
/// animation of every frame run) and the four plots (cycles, error, excess flicker,
/// small-object flicker).
#[test]
fn the_sequence_report_shows_an_animated_image() {
    let Some(chrome) = chromium_or_skip("the_sequence_report_shows_an_animated_image") else {
        return;
    };
    let dir = fresh_dir("browser-sequence");
    igemu(
        &[
            "sequence", "flypast", "--frames", "0..4", "--html", "q.html",
        ],
        &dir,
    );
    let browser = launch(chrome, &dir);
    let tab = open_and_check(&browser, &dir.join("q.html"), 5, &dir.join("sequence.png"));
    let alt = eval(&tab, "document.images[0].alt");
    assert_eq!(alt.as_str(), Some("the frames, at the sequence's rate"));
    // The PNG carries an animation control chunk, and the browser's image decoder (WebCodecs)
    // finds one frame per frame run.
    let js = "(async () => { const s = document.images[0].src; \
              const b = Uint8Array.from(atob(s.slice(s.indexOf(',') + 1)), c => c.charCodeAt(0)); \
              const actl = new TextDecoder('latin1').decode(b.slice(0, 200)).includes('acTL'); \
              if (typeof ImageDecoder === 'undefined') { return JSON.stringify([actl, -1]); } \
              const d = new ImageDecoder({ data: b, type: 'image/png' }); await d.tracks.ready; \
              return JSON.stringify([actl, d.tracks.selectedTrack.frameCount]); })()";
    let v = tab
        .evaluate(js, true)
        .unwrap_or_else(|e| panic!("evaluate: {e}"))
        .value
        .unwrap_or(serde_json::Value::Null);
    let (actl, frames): (bool, i64) =
        serde_json::from_str(v.as_str().expect("a JSON string")).unwrap();
    assert!(actl, "the sequence's image is an APNG (acTL chunk)");
    assert!(
        frames == 4 || frames == -1,
        "the browser decodes {frames} frames, expected 4"
    );
    eprintln!("browser: the sequence's APNG: {frames} frames decoded (-1: no ImageDecoder)");
}
