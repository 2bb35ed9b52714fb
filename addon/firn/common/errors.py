"""Errors meant for the user: operators report their message and change nothing."""


class UserError(Exception):
    """Bad input or a state the user can fix; the message says how."""
