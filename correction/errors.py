"""The base of spherecal's own exceptions: bad input, reported in one line."""


class SpherecalError(Exception):
    """Input that spherecal refuses; the message is one line naming file, row and field."""
