"""Probes that need temporary core hooks (kept as a diff in bench/) refuse to run without them: without the hooks
the core ignores the probe's switches and its numbers would be silently wrong."""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def require_hooks(diff_name):
    """Exits with a message unless bench/`diff_name` is applied to the working tree (the module built from it)."""
    diff = os.path.join(ROOT, "bench", diff_name)
    applied = subprocess.run(["git", "-C", ROOT, "apply", "--reverse", "--check", diff],
                             capture_output=True).returncode == 0
    if not applied:
        sys.exit(f"this probe needs the temporary hooks of bench/{diff_name}: `git apply bench/{diff_name}`, "
                 "rebuild firncore, run, then `git apply -R` it")
