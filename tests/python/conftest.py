import os

import pytest


@pytest.fixture
def tmp_vdb(tmp_path):
    """A path for a VDB file in a fresh temporary folder."""
    return os.fspath(tmp_path / "snow.vdb")


def cancelled_while_running(call, progress):
    """Runs call() on a worker thread; this thread cancels `progress` as soon as the core reports any. That can
    only happen while the core computes if the call released the GIL: otherwise this thread waits until the call
    has returned, the cancel comes too late and no firncore.Cancelled is raised. True if the call was cancelled.
    (The call must be long enough to be still running after its first report: a job of many progress steps.)"""
    import threading
    import time

    import firncore

    outcome = {}

    def work():
        try:
            call()
            outcome["cancelled"] = False
        except firncore.Cancelled:
            outcome["cancelled"] = True

    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive() and progress.fraction == 0.0:
        time.sleep(0.001)
    progress.cancel()
    worker.join()
    return outcome["cancelled"]
