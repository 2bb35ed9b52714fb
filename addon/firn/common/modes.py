"""When operators may run: shared polls (the message says what to do)."""

from .jobs import running_jobs


def object_mode_poll(cls, context):
    """Operators that add objects from the selection run in Object Mode only."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode")
        return False
    return True


def no_job_poll(cls):
    """Operators that bake, simulate or remove a sequence wait while a Firn job runs: the user keeps working beside
    a long job, and a second one would share its processors or write the files it reads."""
    jobs = running_jobs()
    if jobs:
        cls.poll_message_set(f"{jobs[0].label} is running: wait for it or cancel it")
        return False
    return True
