#!/usr/bin/env python3
"""Open flightid reports in headless Chromium, offline, and check that every plot renders.

For each report directory (one holding index.html, as written by `flightid compare`, `flightid demo` or
`flightid campaign report`):
  1. a probe copy of index.html (a small script added at the end) is loaded with `chromium --headless --dump-dom`;
     the script measures every <svg> element and writes the result into the DOM;
  2. the check passes when the number of rendered <svg> elements equals the number in the file and each has a
     non-zero width and height (and, with --expect N, when there are exactly N);
  3. a screenshot of the whole page is written to OUT/<name>.png, and with --figures one PNG per DIR/*.svg
     (960 x 420, the plots' own size) to OUT/<name>/<plot>.png, to look at.

Nothing is fetched: the pages are file:// URLs and the reports are self-contained (inline SVG, no network).

Usage:
  scripts/report_screenshot.py flightid-out/compare flightid-out/demo --out flightid-out/shots [--figures] [--expect 12]
      [--expect-text TEXT ...]
Needs Debian's `chromium` (apt-get install -y chromium), or CHROMIUM=/path/to/chrome. Exit 0 when every report
passes, 1 when one fails, 2 on bad usage.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

PROBE = """
<script>
window.addEventListener('load', function () {
  var svgs = Array.prototype.slice.call(document.querySelectorAll('svg'));
  var sizes = svgs.map(function (s) { var r = s.getBoundingClientRect(); return [r.width, r.height]; });
  var out = document.createElement('pre');
  out.id = 'flightid-probe';
  out.textContent = JSON.stringify({svgs: sizes, height: document.documentElement.scrollHeight,
                                   text: document.body.innerText});
  document.body.appendChild(out);
});
</script>
"""

CHROME_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--no-first-run",
    "--disable-background-networking", "--disable-extensions", "--disable-sync",
    "--no-proxy-server", "--virtual-time-budget=5000",
]


def chromium():
    for name in (os.environ.get("CHROMIUM"), "chromium", "chromium-browser", "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    sys.exit("report_screenshot: no chromium found (apt-get install -y chromium, or set CHROMIUM)")


def run_chrome(browser, profile, args, timeout_s=120):
    cmd = [browser, *CHROME_FLAGS, f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)


def check_report(browser, report_dir, out_dir, figures, expect, texts=()):
    index = os.path.join(report_dir, "index.html")
    if not os.path.isfile(index):
        return False, f"{index}: no such file"
    with open(index, encoding="utf-8") as f:
        html = f.read()
    in_file = len(re.findall(r"<svg\b", html))
    name = os.path.basename(os.path.normpath(os.path.abspath(report_dir)))
    with tempfile.TemporaryDirectory(prefix="flightid-shot-") as tmp:
        probe = os.path.join(tmp, "probe.html")
        with open(probe, "w", encoding="utf-8") as f:
            f.write(html.replace("</body>", PROBE + "</body>"))
        res = run_chrome(browser, os.path.join(tmp, "profile"), ["--dump-dom", "file://" + probe])
        m = re.search(r'<pre id="flightid-probe">(.*?)</pre>', res.stdout, re.S)
        if not m:
            return False, f"{name}: the page did not load in chromium: {res.stderr.strip()[-400:]}"
        probe_text = m.group(1)
        for entity, char in (("&quot;", '"'), ("&lt;", "<"), ("&gt;", ">"), ("&amp;", "&")):
            probe_text = probe_text.replace(entity, char)
        data = json.loads(probe_text)
        sizes = data["svgs"]
        blank = [i for i, (w, h) in enumerate(sizes) if not (w > 0 and h > 0)]
        height = min(int(data["height"]) + 20, 30000)
        shot = os.path.join(out_dir, f"{name}.png")
        run_chrome(browser, os.path.join(tmp, "profile"),
                   [f"--screenshot={os.path.abspath(shot)}", f"--window-size=1200,{height}",
                    "file://" + os.path.abspath(index)])
        if figures:
            fig_dir = os.path.join(out_dir, name)
            os.makedirs(fig_dir, exist_ok=True)
            for svg in sorted(os.listdir(report_dir)):
                if svg.endswith(".svg"):
                    png = os.path.join(fig_dir, svg[:-4] + ".png")
                    run_chrome(browser, os.path.join(tmp, "profile"),
                               [f"--screenshot={os.path.abspath(png)}", "--window-size=960,420",
                                "file://" + os.path.abspath(os.path.join(report_dir, svg))])
    problems = []
    if len(sizes) != in_file:
        problems.append(f"{len(sizes)} svg rendered of {in_file} in the file")
    if blank:
        problems.append(f"svg number(s) {blank} rendered with zero size")
    if expect is not None and in_file != expect:
        problems.append(f"expected {expect} figures, the file has {in_file}")
    missing = [t for t in texts if t not in data.get("text", "")]
    if missing:
        problems.append("text not shown on the rendered page: " + "; ".join(repr(t) for t in missing))
    if not os.path.isfile(shot) or os.path.getsize(shot) == 0:
        problems.append("no screenshot written")
    summary = f"{name}: {len(sizes) - len(blank)}/{in_file} figures rendered, page {height} px, screenshot {shot}"
    return not problems, summary + ("" if not problems else " -- " + "; ".join(problems))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("reports", nargs="+", help="report directories (each holding index.html)")
    ap.add_argument("--out", default="report-screenshots", help="where the PNGs go")
    ap.add_argument("--figures", action="store_true", help="also one PNG per plot")
    ap.add_argument("--expect", type=int, help="exact number of figures every report must hold")
    ap.add_argument("--expect-text", action="append", default=[],
                    help="text that must be visible on every rendered page (repeatable)")
    a = ap.parse_args()
    browser = chromium()
    os.makedirs(a.out, exist_ok=True)
    ok_all = True
    for r in a.reports:
        ok, line = check_report(browser, r, a.out, a.figures, a.expect, a.expect_text)
        print(("ok    " if ok else "FAIL  ") + line)
        ok_all &= ok
    sys.exit(0 if ok_all else 1)


if __name__ == "__main__":
    main()
