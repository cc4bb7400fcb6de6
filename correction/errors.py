"""The base of spherecal's own exceptions: bad input, reported in one line."""


class SpherecalError(Exception):
    """Input that spherecal refuses; the message is one line naming file, row and field."""


class ShapeError(SpherecalError, ValueError):
    """An array of the wrong shape for the robot (joint angles ``q`` of another arm's joint count, ...). A
    ``ValueError`` too, as numpy's shape errors are."""
