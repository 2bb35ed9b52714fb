"""When operators may run: shared polls (the message says what to do)."""


def object_mode_poll(cls, context):
    """Operators that add objects from the selection run in Object Mode only."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode")
        return False
    return True
