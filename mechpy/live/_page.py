"""The live widget and its saved page: one ES module per view, run the same way
in a notebook (anywidget) and in a saved HTML file (a small stand-in for the
widget's model).

A view is ``static/<view>.js`` with ``export default {render}``, preceded by
``static/common.js`` (helpers every view uses, no imports) and, for the 3D
views, three.js's modules as strings that ``mpThree()`` loads from blob URLs.
Nothing is fetched: the module is one string, in the notebook (anywidget loads
``_esm`` from a blob) and in the saved page (inlined as JSON).
"""
from __future__ import annotations

import base64
import functools
import json
from pathlib import Path

import numpy as np

try:
    import anywidget
    import traitlets
except ImportError as e:     # pragma: no cover - the live extra is missing
    raise ImportError("mechpy.live needs anywidget: pip install \"mechpy-classical[live]\" "
                      "(or pip install anywidget)") from e

_STATIC = Path(__file__).with_name("static")

#: three.js files (static/vendor, npm three@0.180.0), in the order they load
_THREE = ("three.core.min.js", "three.module.min.js", "OrbitControls.js")


@functools.lru_cache(maxsize=None)
def _read(name: str) -> str:
    return (_STATIC / name).read_text(encoding="utf-8")


@functools.lru_cache(maxsize=None)
def esm(view: str, three: bool = False, extra: tuple = ()) -> str:
    """The ES module of ``view``: common.js, three.js's sources when asked, the
    ``extra`` files (static/, helpers the view calls when its spec asks), the view."""
    parts = [_read("common.js")]
    if three:
        srcs = {name: _read("vendor/" + name) for name in _THREE}
        parts.append("const MP_THREE_SOURCES = " + json.dumps(srcs) + ";")
    parts += [_read(name) for name in extra]
    parts.append(_read(view + ".js"))
    return "\n".join(parts)


def pack(a, dtype="<f8") -> str:
    """An array as base64 of its little-endian bytes (``mpUnpack`` in common.js)."""
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _script_json(obj) -> str:
    """JSON safe inside a <script> element (no '</' and no '<!--')."""
    return json.dumps(obj, separators=(",", ":")).replace("</", "<\\/").replace("<!--", "<\\!--")


_BOOT = """
const el = document.getElementById("mechpy-live");
const state = JSON.parse(document.getElementById("mechpy-state").textContent);
const src = JSON.parse(document.getElementById("mechpy-esm").textContent);
const handlers = {};
const model = {
  get: (k) => state[k],
  set: (k, v) => { state[k] = v; (handlers["change:" + k] || []).forEach((f) => f()); },
  on: (ev, f) => { (handlers[ev] = handlers[ev] || []).push(f); },
  off: (ev, f) => { if (ev) handlers[ev] = (handlers[ev] || []).filter((g) => f && g !== f); },
  save_changes: () => {},
  send: () => {},
};
const url = URL.createObjectURL(new Blob([src], {type: "text/javascript"}));
const mod = await import(url);
await mod.default.render({model, el});
// shown in an iframe (the docs site, an exported notebook: LiveWidget.iframe), the page sets
// the frame's height to its own, so that controls wrapped in a narrow column stay in view
// (a frame of another origin refuses: it keeps the height it was given)
let frame = null;
try { frame = window.frameElement; } catch (e) { frame = null; }
if (frame) {
  const fit = () => { frame.style.height = `${Math.ceil(document.body.getBoundingClientRect().height)}px`; };
  new ResizeObserver(fit).observe(document.body);
  fit();
}
"""


class LiveWidget(anywidget.AnyWidget):
    """Base of the live views: the view's spec (one JSON-able dict), and
    :meth:`save` for a page that runs without a kernel."""

    #: everything the page needs, JSON-able (arrays packed with :func:`pack`)
    spec = traitlets.Dict().tag(sync=True)
    #: True only in a saved page (no kernel to ask)
    _offline = traitlets.Bool(False).tag(sync=True)

    _view = ""
    _three = False

    def __init__(self, spec: dict, extra: tuple = (), **kwargs):
        super().__init__(spec=spec, _esm=esm(self._view, self._three, tuple(extra)), **kwargs)
        self._extra = tuple(extra)
        self.on_msg(self._on_page_message)

    def _on_page_message(self, widget, content, buffers):
        """A request from the page (a view overrides :meth:`_answer`)."""
        if not isinstance(content, dict):
            return
        try:
            reply = self._answer(content)
        except Exception as e:          # the page shows the message, the kernel lives on
            reply = {"type": "error", "id": content.get("id"), "message": f"{type(e).__name__}: {e}"}
        if reply is not None:
            reply.setdefault("id", content.get("id"))
            self.send(reply)

    def _answer(self, content: dict):
        return None

    def _repr_mimebundle_(self, **kwargs):
        """The widget for a live kernel, and beside it the saved page in an
        iframe (``text/html``) for what shows a notebook without one: the docs
        site, nbviewer, an exported notebook.  Jupyter front ends prefer the
        widget."""
        data = super()._repr_mimebundle_(**kwargs)
        if isinstance(data, tuple):
            data = data[0]
        if data is None:
            data = {}
        data = dict(data)
        data["text/html"] = self.iframe()
        return data

    def iframe(self) -> str:
        """The saved page (:meth:`html`) as an ``<iframe srcdoc=...>``: as wide as the view
        at most, narrower in a narrower column (the view follows it), and as high as the
        page's content once it has rendered (the page sets its frame's height)."""
        w, h = self._frame_size()
        return (f'<iframe title="{_escape(self._view)}" style="display:block;border:0;width:{w}px;'
                f'max-width:100%;height:{h}px" srcdoc="{_escape(self.html())}"></iframe>')

    def _frame_size(self):
        return (int(self.spec.get("width", 720)) + 40, int(self.spec.get("height", 480)) + 110)

    def html(self, title: str = "mechpy live view") -> str:
        """The page as one self-contained HTML string (see :meth:`save`)."""
        state = {"spec": self.spec, "_offline": True}
        return (
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{_escape(title)}</title>"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            "<style>body{margin:0;padding:12px;font-family:system-ui,sans-serif;"
            "background:#fff}</style></head><body>"
            "<div id=\"mechpy-live\"></div>"
            f"<script type=\"application/json\" id=\"mechpy-state\">{_script_json(state)}</script>"
            "<script type=\"application/json\" id=\"mechpy-esm\">"
            f"{_script_json(esm(self._view, self._three, self._extra))}</script>"
            f"<script type=\"module\">{_BOOT}</script></body></html>\n")

    def save(self, path, *, title: str = "mechpy live view") -> Path:
        """Write the view as one HTML file that runs offline.

        Every script is inline (three.js included for the 3D views); the page
        makes no network request.  What needs a kernel falls back to what the
        page has: overlays precomputed over the sliders' ranges, trajectories
        integrated by the page itself.

        Parameters
        ----------
        path : str or path-like
            The file to write (``.html``).
        title : str
            The page's title.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        path = Path(path)
        path.write_text(self.html(title), encoding="utf-8")
        return path


def _escape(s: str) -> str:
    return (str(s).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;"))
