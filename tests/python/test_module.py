"""The core module under plain /usr/bin/python3, without Blender."""

import re
import sys

import pytest

import firncore


def test_runs_without_blender():
    assert "bpy" not in sys.modules
    assert sys.executable.startswith("/usr/bin/python3") or sys.version_info[:2] == (3, 11)


def test_version_is_semantic():
    assert re.fullmatch(r"\d+\.\d+\.\d+", firncore.__version__)


def test_progress_cancel_flag():
    progress = firncore.Progress()
    assert progress.fraction == 0.0
    assert not progress.cancelled
    progress.cancel()
    assert progress.cancelled


def test_thread_count_rejects_negative():
    with pytest.raises(ValueError, match="thread count"):
        firncore.set_thread_count(-1)
    firncore.set_thread_count(1)
    firncore.set_thread_count(0)
    assert firncore.hardware_threads() >= 1


def test_errors_are_python_exceptions():
    assert issubclass(firncore.BudgetError, ValueError)
    assert issubclass(firncore.Cancelled, Exception)
