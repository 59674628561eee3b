"""diagnose --report's report.html rendered by a headless browser (Chromium's headless shell):
the page loads without error, its DOM holds the verdict first, the report's tables and the three
plots inline, and a screenshot is drawn. Run by scripts/test.sh (setup.sh installs
chromium-headless-shell); `python scripts/check_report_html.py [--physid PATH]`."""
import os
import re
import shutil
import subprocess
import sys
import tempfile
from html.parser import HTMLParser

from physid_common import KUKA_URDF, ROOT, arguments, physid_bin, run

BROWSERS = ["chromium-headless-shell", "chromium", "chromium-browser", "google-chrome"]


class Dom(HTMLParser):
    """Counts the elements the checks need and the text of the first body elements."""

    def __init__(self):
        super().__init__()
        self.counts = {}
        self.first = []
        self.order = []
        self.classes = []

    def handle_starttag(self, tag, attrs):
        self.order.append(tag)
        self.counts[tag] = self.counts.get(tag, 0) + 1
        if tag in ("h1", "p", "h2", "table") and len(self.first) < 3:
            self.first.append(tag)
            self.classes.append(dict(attrs).get("class"))


def png_rows(path):
    """Rows of an 8-bit RGB or RGBA PNG as bytes (a minimal decoder: zlib and the five filters)."""
    import struct
    import zlib
    data = open(path, "rb").read()
    pos, idat, width, height, channels = 8, b"", 0, 0, 3
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color = struct.unpack(">IIBB", chunk[:10])
            assert depth == 8 and color in (2, 6), "8-bit RGB(A) only"
            channels = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            p = a + b - c
            pred = [0, a, b, (a + b) // 2, a if abs(p - a) <= min(abs(p - b), abs(p - c)) else (b if abs(p - b) <= abs(p - c) else c)][f]
            line[i] = (line[i] + pred) & 0xFF
        rows.append((bytes(line), channels))
        prev = line
    return rows


def colored_rows(path):
    """Indices of the screenshot's rows that hold saturated colour (a plot's bars; the page's
    text and tables are grey)."""
    out = []
    for y, (row, ch) in enumerate(png_rows(path)):
        for x in range(0, len(row), ch * 4):
            r, g, b = row[x], row[x + 1], row[x + 2]
            if max(r, g, b) - min(r, g, b) > 80:
                out.append(y)
                break
    return out


def main():
    binary = physid_bin(arguments(__doc__).physid)
    browser = next((b for b in BROWSERS if shutil.which(b)), None)
    passed = failed = 0

    def check(name, ok, detail=""):
        nonlocal passed, failed
        print(f"{'ok  ' if ok else 'FAIL'} {name}{': ' + detail if detail and not ok else ''}")
        passed += ok
        failed += not ok

    if browser is None:
        check("a headless browser is installed", False, "install chromium-headless-shell (bash scripts/setup.sh does)")
        print(f"{passed} passed, {failed} failed")
        return 1
    k = os.path.join(ROOT, "data", "kuka_lwr4")
    with tempfile.TemporaryDirectory() as d:
        report = os.path.join(d, "report")
        run(binary, "diagnose", "--robot", KUKA_URDF, "--constraints", "consistent",
            "--data", os.path.join(k, "measurements_1.csv"), os.path.join(k, "measurements_2.csv"),
            "--validate", os.path.join(k, "measurements_3.csv"), "--report", report)
        page = "file://" + os.path.join(report, "report.html")
        flags = ["--headless", "--no-sandbox", "--disable-gpu", "--window-size=1200,2400"]
        dom = subprocess.run([browser, *flags, "--dump-dom", page], capture_output=True, text=True, timeout=120)
        check("the browser loads report.html", dom.returncode == 0 and "</html>" in dom.stdout,
              dom.stderr[-500:])
        errors = [l for l in dom.stderr.splitlines() if "Uncaught" in l or "CONSOLE" in l and "error" in l.lower()]
        check("no console errors", not errors, "\n".join(errors))
        parsed = Dom()
        parsed.feed(dom.stdout)
        check("the title, then the verdict first", parsed.first[:2] == ["h1", "p"] and parsed.classes[1] == "verdict",
              f"{parsed.first} {parsed.classes}")
        verdict = re.search(r"Verdict: <b>([a-z_]+)</b>", dom.stdout)
        check("the verdict is one of the documented ones", verdict is not None and verdict.group(1) in
              ("no_effect", "explained", "partially_explained", "unexplained", "absorbed", "undecided"),
              verdict.group(0) if verdict else "none")
        check("the report's tables", parsed.counts.get("table", 0) >= 6, str(parsed.counts.get("table")))
        check("three plots inline", parsed.counts.get("svg", 0) == 3, str(parsed.counts.get("svg")))
        check("no external resource", "src=\"http" not in dom.stdout and "<script" not in dom.stdout)
        order = parsed.order
        first = lambda tag: order.index(tag) if tag in order else len(order)
        check("the plots come before the tables, which are folded", first("svg") < first("table") and
              first("details") < first("table") and parsed.counts.get("details", 0) >= 3,
              f"svg {first('svg')}, details {first('details')}, table {first('table')}")
        screen = os.path.join(d, "screen.png")
        res = subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--window-size=1200,900",
                              f"--screenshot={screen}", page], capture_output=True, text=True, timeout=120)
        colored = colored_rows(screen) if res.returncode == 0 and os.path.exists(screen) else []
        check("the first screen (1200 x 900) shows the verdict and a plot: coloured bars below the verdict",
              len(colored) > 50 and max(colored) > 300, f"{len(colored)} rows with plot colours")
        shot = os.path.join(d, "shot.png")
        res = subprocess.run([browser, *flags, f"--screenshot={shot}", page], capture_output=True, text=True, timeout=120)
        ok = res.returncode == 0 and os.path.exists(shot)
        size = os.path.getsize(shot) if ok else 0
        with open(shot, "rb") if ok else open(os.devnull, "rb") as f:
            magic = f.read(8)
        check("a screenshot is drawn", ok and magic == b"\x89PNG\r\n\x1a\n" and size > 50_000, f"{size} bytes")
    print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
