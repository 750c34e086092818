"""Pages in a real browser (the ``browser`` fixture of conftest.py: Debian's headless
Chromium driven by Playwright): a page opened and drawn, the body's surfaces as drawn, a
screenshot's pixels."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np


def open_page(browser, path: Path):
    """The report in a new page, drawn; and the list its console errors go to."""
    page = browser.new_page(viewport={"width": 1400, "height": 1200})
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.resolve().as_uri())
    page.wait_for_function("window.reportReady === true", timeout=60_000)
    return page, errors


def mesh_of(page) -> dict[str, np.ndarray]:
    """The body's surfaces as drawn: vertices (n × 3 [m]) by trace name."""
    traces = page.evaluate(
        "document.getElementById('body').data.filter(t => t.type === 'mesh3d')"
        ".map(t => [t.name, t.x, t.y, t.z])"
    )
    return {name: np.c_[x, y, z] for name, x, y, z in traces if name != "floor" and len(x) > 4}


def pixels_of(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
