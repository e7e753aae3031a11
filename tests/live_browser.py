"""The live views' tests drive pages in headless Chromium (mechpy.live._browser)."""
import os

import pytest

from mechpy.live._browser import (available, browser, network_requests, open_page,  # noqa: F401
                                  wait_for)


@pytest.fixture(scope="module")
def driver():
    why = available()
    if why:
        if os.environ.get("CI"):    # CI installs them (scripts/dev.sh): missing is a failure
            pytest.fail(why)
        pytest.skip(why)
    d = browser()
    try:
        yield d
    finally:
        d.quit()
