"""Long core calls without freezing Blender: a worker thread that never touches bpy, a modal timer that
shows its progress and cancels it with Esc.

An operator using FirnJobMixin splits its work in three:
    prepare(context) -> inputs         main thread: reads bpy, raises UserError for bad input
    compute(inputs, progress) -> out   worker thread: core calls only (they release the GIL), no bpy
    apply(context, inputs, out)        main thread: writes the results into Blender
execute() runs the three in a row (scripts, redo, background mode); invoke() runs compute in a worker.
While a job runs, the status bar shows its progress and a Cancel button (as does Esc). Long jobs (Bake Scattering,
Add Snow Spray, Bake Sequence, Bake Light Sequence) set `job_passes_events` so the user keeps working meanwhile:
their polls refuse a second such job (modes.no_job_poll) and their apply() finds its objects again by name, any of
which the user may have deleted. Short ones hold the input until they end.
"""

import os
import threading

import bpy

from .core import firncore
from .errors import UserError

_TIMER_INTERVAL = 0.1  # s
_WORKER_NICENESS = 5  # the worker yields the processor to Blender's UI (and its drawing, in software GL)
_running = []  # jobs started from the UI, until their operator ends
idle_hooks = []  # called once the last running job has ended and applied its result (cache.py registers one)


def running_jobs():
    """Jobs whose operator has not ended: computing, or done and waiting for the operator's next timer event to
    apply the result (a new job on the same data waits for that too)."""
    return list(_running)


class Job:
    """compute(inputs, progress) on a worker thread; the main thread polls `done` and `progress`, and keeps
    `status` (what the status bar and panels show) up to date."""

    def __init__(self, compute, inputs, label="Firn"):
        self.label = label
        self.status = ""
        self.progress = firncore.Progress()
        self.result = None
        self.error = None
        self._thread = threading.Thread(target=self._run, args=(compute, inputs), name="firn-job", daemon=True)

    def _run(self, compute, inputs):
        _lower_priority()
        try:
            self.result = compute(inputs, self.progress)
        except BaseException as error:  # handed to the main thread, which reports it
            self.error = error

    def start(self):
        self._thread.start()

    @property
    def done(self):
        return not self._thread.is_alive()

    def cancel(self):
        self.progress.cancel()

    def wait(self):
        self._thread.join()


def _lower_priority():
    """Lowers the calling thread's scheduling priority (Linux: niceness is per thread)."""
    try:
        thread = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, thread, max(os.getpriority(os.PRIO_PROCESS, thread), _WORKER_NICENESS))
    except (AttributeError, OSError):  # no per-thread priority here: the job runs at the UI's priority
        pass


class FirnJobMixin:
    """Operator mixin: see the module docstring. Subclasses set `job_label` and the three methods."""

    job_label = "Firn"
    job_passes_events = False

    def job_status(self, inputs, progress):
        """What the job is doing, for the status bar; jobs of several parts say which one."""
        return progress.stage

    def execute(self, context):
        try:
            inputs = self.prepare(context)
            result = self.compute(inputs, firncore.Progress())
            return self._finish(context, inputs, result)
        except UserError as error:
            self.report({"ERROR"}, str(error))
        except (ValueError, OSError, firncore.Cancelled) as error:
            self.report({"ERROR"}, f"{self.job_label}: {error}")
        return {"CANCELLED"}

    def invoke(self, context, _event):
        if bpy.app.background:
            return self.execute(context)
        try:
            inputs = self.prepare(context)
        except UserError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._inputs = inputs
        self._job = Job(self.compute, inputs, self.job_label)
        self._job.start()
        _running.append(self._job)
        wm = context.window_manager
        self._timer = wm.event_timer_add(_TIMER_INTERVAL, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        cancels = event.type == "ESC" and event.value == "PRESS" and not (self.job_passes_events and _playing(context))
        if cancels:
            self._job.cancel()
        if event.type != "TIMER":
            passes = self.job_passes_events and not cancels
            return {"PASS_THROUGH"} if passes else {"RUNNING_MODAL"}
        job = self._job
        percent = int(100 * job.progress.fraction)
        job.status = f"{self.job_status(self._inputs, job.progress)} {percent}%"
        context.window_manager.progress_update(percent)
        context.workspace.status_text_set(f"{self.job_label}: {job.status}   (Esc to cancel)")
        if self.job_passes_events:  # the user is looking around: the panels show the progress too
            _redraw_panels(context)
        if not job.done:
            return {"PASS_THROUGH"}
        self._end_modal(context)
        try:
            return self._conclude(context, job)
        finally:
            if not _running:
                for hook in idle_hooks:
                    hook()

    def _conclude(self, context, job):
        """The ended job's result applied, or its error or cancel reported."""
        if isinstance(job.error, firncore.Cancelled):
            self.report({"INFO"}, f"{self.job_label} cancelled: nothing changed")
            return {"CANCELLED"}
        if job.error is not None:
            if not isinstance(job.error, (ValueError, OSError, UserError)):
                raise job.error
            self.report({"ERROR"}, f"{self.job_label}: {job.error}")
            return {"CANCELLED"}
        try:
            return self._finish(context, self._inputs, job.result)
        except UserError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}

    def cancel(self, context):
        """Blender drops the operator (a file load, quitting): the job stops and its result is not applied."""
        self._job.cancel()
        self._end_modal(context)

    def _end_modal(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        _running.remove(self._job)
        if not _running:  # a short job ended beside a long one: the long one's progress and status go on
            wm.progress_end()
            context.workspace.status_text_set(None)
        if self.job_passes_events:
            _redraw_panels(context)

    def _finish(self, context, inputs, result):
        self.apply(context, inputs, result)
        return {"FINISHED"}


def _playing(context):
    """The animation plays: Esc stops it (a user scrubbing and playing beside a long job), not the job."""
    return context.screen is not None and context.screen.is_animation_playing


def scene_left(operator, context, scene_name):
    """True, with a warning, when the active scene is no longer the job's `scene_name`: the user switched scenes while
    the job ran, and what it adds would land in the other scene (its files stay and a new run reuses them)."""
    if context.scene.name == scene_name:
        return False
    operator.report({"WARNING"}, f"{operator.bl_label} ended while another scene was shown: nothing was added. "
                                 f"Show '{scene_name}' and run it again: what it already made is reused")
    return True


def select_only(context, obj):
    """A job's new object becomes the selection, unless the user went on into another mode meanwhile (or made a
    collection outside the view layer active, where the object went)."""
    if context.mode != "OBJECT" or obj.name not in context.view_layer.objects:
        return
    for other in context.selected_objects:
        other.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj


def _redraw_panels(context):
    """The panels that show a long job's progress (Firn sidebar, Properties) follow it."""
    for area in context.screen.areas if context.screen else ():
        if area.type in {"VIEW_3D", "PROPERTIES"}:
            for region in area.regions:
                if region.type in {"UI", "WINDOW"} and not (area.type == "VIEW_3D" and region.type == "WINDOW"):
                    region.tag_redraw()


class FIRN_OT_cancel_jobs(bpy.types.Operator):
    """Stop Firn's running jobs: what they would have changed stays as it was"""

    bl_idname = "firn.cancel_jobs"
    bl_label = "Cancel"

    @classmethod
    def poll(cls, _context):
        if not running_jobs():
            cls.poll_message_set("No Firn job is running")
            return False
        return True

    def execute(self, _context):
        for job in running_jobs():
            job.cancel()
        return {"FINISHED"}


def _draw_status(self, _context):
    """The status bar's Cancel button while a job runs (its progress is the status text)."""
    jobs = running_jobs()
    if jobs:
        self.layout.operator(FIRN_OT_cancel_jobs.bl_idname, text=f"Cancel {jobs[0].label}", icon="CANCEL")


classes = (FIRN_OT_cancel_jobs,)


def register_extras():
    bpy.types.STATUSBAR_HT_header.prepend(_draw_status)


def unregister_extras():
    bpy.types.STATUSBAR_HT_header.remove(_draw_status)
