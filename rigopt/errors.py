"""The exceptions rigopt raises for bad input; each message says what is wrong and how to fix it.

The CLI prints any :class:`RigoptError` as one line and exits with code 2.
"""


class RigoptError(Exception):
    """Base of every error caused by the user's input (files, names, values)."""


class RigFileError(RigoptError, ValueError):
    """A rig file or rig value is malformed: missing keys, wrong types, NaN/inf, no cameras."""


class UnknownNameError(RigoptError, LookupError):
    """A rig, vehicle or weights name is not known; the message lists the valid names."""


class DataError(RigoptError, ValueError):
    """Transfer results, weights or other data files are malformed or inconsistent."""


def unknown_name(kind: str, name: str, valid) -> UnknownNameError:
    """Build the error for an unknown ``name`` of ``kind``, listing the ``valid`` names."""
    return UnknownNameError(f"unknown {kind} {name!r}; valid names: {', '.join(valid)}")


def not_utf8(path, what: str, error: UnicodeDecodeError, kind: type[RigoptError] = DataError) -> RigoptError:
    """Build the error for a ``what`` file at ``path`` that is not UTF-8 text (``error`` from decoding it)."""
    return kind(f"{path}: the {what} is not UTF-8 text (byte {error.start} is {error.object[error.start]:#04x}); "
                "save it as UTF-8")


def json_loads(text: str):
    """``json.loads``, whose RecursionError on arrays or objects nested past Python's limit (about a thousand
    levels: no file rigopt reads nests more than a few) comes back as the JSONDecodeError every reader turns into
    its one-line error."""
    import json

    try:
        return json.loads(text)
    except RecursionError:
        raise json.JSONDecodeError("arrays or objects nested too deeply (over a thousand levels)", text, 0) from None
