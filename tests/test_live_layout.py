"""The live views fit the column they are shown in: a view is as wide as its container
with its ``width=`` (the phase portrait) as the most it takes, its canvases' pixels follow
a resize, and a view shown through ``LiveWidget.iframe()`` (the docs site, an exported
notebook) sets its frame's height to its content.  Checked in headless Chromium on a
page that holds the frame in a column of a given width."""
from __future__ import annotations

import numpy as np
import pytest

import mechpy as mp

pytest.importorskip("anywidget")
from live_browser import driver, network_requests, wait_for  # noqa: E402,F401

#: the saved page's own margin (LiveWidget.html: body padding 12 px each side)
PAD = 2 * 12


def _in_column(driver, tmp_path, w, column, name):
    """Open a page holding ``w.iframe()`` in a column ``column`` px wide; switch into the
    frame once its view is ready."""
    host = tmp_path / f"{name}.html"
    host.write_text("<!DOCTYPE html><html><body style='margin:0'>"
                    f"<div id='col' style='width:{column}px'>{w.iframe()}</div>"
                    "<p id='after'>after the frame</p></body></html>")
    network_requests(driver)
    driver.switch_to.default_content()
    driver.get(f"file://{host}")
    driver.switch_to.frame(driver.find_element("tag name", "iframe"))
    wait_for(driver, "window.mechpyLive && window.mechpyLive.ready", 60)
    return host


def _layout(driver, canvas_selector):
    """(canvas pixels wide, high; CSS width of the canvas; the frame page overflows
    sideways; its content height; the frame's height), read in the frame and then in
    the host page."""
    inside = driver.execute_script(f"""
        const c = document.querySelector({canvas_selector!r});
        const d = document.documentElement;
        return [c.width, c.height, c.getBoundingClientRect().width,
                d.scrollWidth > d.clientWidth,
                Math.ceil(document.body.getBoundingClientRect().height)];""")
    driver.switch_to.default_content()
    frame_h = driver.execute_script(
        "return document.querySelector('iframe').getBoundingClientRect().height")
    driver.switch_to.frame(driver.find_element("tag name", "iframe"))
    return inside + [frame_h]


def _column_width(driver, px):
    driver.switch_to.default_content()
    driver.execute_script(f"document.getElementById('col').style.width = '{px}px'")
    driver.switch_to.frame(driver.find_element("tag name", "iframe"))


PHASE = "canvas"                        # the particles' canvas is the page's first


def test_phase_portrait_fits_a_narrow_column_and_follows_it(driver, tmp_path):
    w = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6),
                               params={"mu": (0.0, 4.0)}, particles=500, overlays=False,
                               play=False, width=720, height=300)
    _in_column(driver, tmp_path, w, 500, "narrow")
    assert network_requests(driver) == []
    cw, ch, css_w, overflow, body_h, frame_h = _layout(driver, PHASE)
    # the column (500 px) less the page's margin; the given height kept
    assert (cw, ch, css_w, overflow) == (500 - PAD, 300, 500 - PAD, False)
    assert frame_h == pytest.approx(body_h, abs=1)             # every control in view
    # the view still runs: a step moves the particles
    seeds = np.array(driver.execute_script("return Array.from(window.mechpyLive.seeds())"))
    driver.execute_script("window.mechpyLive.step(10)")
    moved = np.array(driver.execute_script("return Array.from(window.mechpyLive.particles())"))
    assert np.abs(moved - seeds).max() > 1e-3
    # the column narrows: the canvases follow (pixels and overlay alike), the frame too
    _column_width(driver, 380)
    wait_for(driver, f"document.querySelector('canvas').width === {380 - PAD}", 10)
    cw, ch, css_w, overflow, body_h, frame_h = _layout(driver, PHASE)
    assert (cw, ch, css_w, overflow) == (380 - PAD, 300, 380 - PAD, False)
    assert driver.execute_script("return document.querySelectorAll('canvas')[1].width") == cw
    wait_for(driver, "Math.abs(window.frameElement.getBoundingClientRect().height - "
                     "document.body.getBoundingClientRect().height) <= 1", 10)
    # a column wider than width=: the view takes width= and no more
    _column_width(driver, 1100)
    wait_for(driver, "document.querySelector('canvas').width === 720", 10)
    driver.execute_script("window.mechpyLive.step(1)")           # draws at the new size
    assert network_requests(driver) == []


def test_phase_portrait_saved_page_keeps_its_width(driver, tmp_path):
    """A saved page in a window wider than the view: exactly width= by height=."""
    w = mp.live.phase_portrait(mp.scenes.Pendulum(), (-4, 4), (-5, 5), particles=200,
                               overlays=False, play=False, width=333, height=222)
    path = w.save(tmp_path / "fixed.html")
    driver.switch_to.default_content()
    driver.get(f"file://{path}")
    wait_for(driver, "window.mechpyLive && window.mechpyLive.ready", 60)
    sizes = driver.execute_script("return Array.from(document.querySelectorAll('canvas'), "
                                  "(c) => [c.width, c.height, c.getBoundingClientRect().width])")
    assert sizes == [[333, 222, 333], [333, 222, 333]]


def test_animate_fits_a_narrow_column(driver, tmp_path):
    p = mp.scenes.Pendulum(length=1.0)
    sol = mp.solve(p, (0, 2), [1.0, 0.0], dense_output=True, rtol=1e-9)
    w = mp.live.animate(p, sol, fps=10)
    _in_column(driver, tmp_path, w, 420, "animate")
    cw, ch, css_w, overflow, body_h, frame_h = _layout(driver, ".mechpy-animate canvas")
    inner = 420 - PAD - 2                                       # the stage's 1 px border
    assert css_w == pytest.approx(inner, abs=0.5) and not overflow
    css_h = driver.execute_script("return document.querySelector('.mechpy-animate canvas')"
                                  ".getBoundingClientRect().height")
    assert css_h == pytest.approx(round(0.62 * inner), abs=0.5)  # the view's aspect kept
    assert frame_h == pytest.approx(body_h, abs=1)
    _column_width(driver, 600)
    wait_for(driver, "Math.abs(document.querySelector('.mechpy-animate canvas')"
                     f".getBoundingClientRect().width - {600 - PAD - 2}) < 0.5", 10)
    t = driver.execute_script("return window.mechpyLive.frame(5)")
    assert t == w.times[5]
