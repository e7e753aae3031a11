"""The README's picture: a live phase portrait (Van der Pol) photographed in headless
Chromium, as scripts/live_screenshots.py photographs the docs' views, then reduced to a
palette PNG under 200 kB (docs/images/readme-vanderpol.png).

Run from a clone after set-up: ``.venv/bin/python scripts/readme_image.py``.
"""
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image, ImageChops

import mechpy as mp
from mechpy.live import _browser

OUT = Path(__file__).resolve().parent.parent / "docs" / "images" / "readme-vanderpol.png"
LIMIT = 200_000   # bytes (tests/test_readme.py)


def main():
    why = _browser.available()
    if why:
        sys.exit(why)
    w = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6),
                               params={"mu": (0.0, 4.0)})
    tmp = Path(tempfile.mkdtemp())
    d = _browser.browser()
    try:
        _browser.open_page(d, w.save(tmp / "vanderpol.html"))
        time.sleep(3.0)   # the particles' trails fill in
        d.find_element("css selector", ".mechpy-live").screenshot(str(tmp / "shot.png"))
    finally:
        d.quit()
    img = Image.open(tmp / "shot.png").convert("RGB")
    # the widget's box is wider than its canvas and controls: the page's white cut off
    box = ImageChops.difference(img, Image.new("RGB", img.size, "white")).getbbox()
    img = img.crop((0, 0, min(img.width, box[2] + 8), img.height))
    for colours in (128, 64, 32):
        img.quantize(colors=colours, method=Image.Quantize.MEDIANCUT).save(OUT, optimize=True)
        if OUT.stat().st_size < LIMIT:
            break
    print("wrote", OUT, img.size, OUT.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
