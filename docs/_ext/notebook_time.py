"""A notebook that the docs build executes and that takes longer than its bound
fails the build (a warning under ``-W``), naming the notebook and its time.

Why: a cold build once waited 626 s on phase_portraits, a notebook that runs in
about 20 s: 600 s, the cell limit then, plus the notebook's own time.  Its
``ipywidgets.interact`` cell draws an inline figure inside an ``Output`` widget;
nbclient, standing in for a browser, answers each output captured by that widget
with a ``comm_msg`` that it sends on the kernel's shell channel
(``nbclient.output_widget.OutputWidget.sync_state``) while it awaits the cell's
``execute_reply`` on that same channel: one such message per run of the cell with
the inline backend the docs use, none with Agg (``tests/test_notebooks.py``, where
the figure is not a display output).  The likely cause is nbclient issue 312
(open upstream: executing a cell with ipywidgets "sometimes blocks"): the wait
misses the reply that has arrived and returns only when the cell's timeout fires,
when pyzmq's last poll finds the reply, so the cell ends without an error, late
by the whole timeout.  It is intermittent (twelve runs of the cell here did not
stall).

``nb_execution_timeout`` (``docs/conf.py``) bounds such a wait; this check
makes it visible: a notebook executed by this build whose run took more than
``mechpy_notebook_max_seconds`` fails the build.  A notebook taken from the
execution cache (executed by an earlier build) is not checked again.
"""
import time

from sphinx.util import logging

logger = logging.getLogger(__name__)
_BUILD_START = [0.0]          # set by setup(): when this build began


def check_notebook_time(app, doctree):
    env = app.env
    data = getattr(env, "nb_metadata", {}).get(env.docname, {}).get("exec_data")
    if not data or data.get("runtime") is None:
        return
    if data.get("mtime", 0.0) < _BUILD_START[0]:
        return                     # from the execution cache: run by an earlier build
    limit = app.config.mechpy_notebook_max_seconds
    if data["runtime"] > limit:
        logger.warning(
            f"{env.docname}: executing the notebook took {data['runtime']:.0f} s, more than "
            f"{limit:g} s (mechpy_notebook_max_seconds in docs/conf.py; the notebooks run in "
            "under a minute): a cell stalled, as widget cells do when nbclient misses the "
            "kernel's reply until nb_execution_timeout (see docs/_ext/notebook_time.py)",
            type="mechpy", subtype="notebook_time", location=env.docname)


def setup(app):
    app.add_config_value("mechpy_notebook_max_seconds", 90.0, "env", types=(int, float))
    _BUILD_START[0] = time.time()
    app.connect("doctree-read", check_notebook_time)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
