"""The exceptions physid raises, all under `physid.Error`.

Each is also the built-in exception a Python user expects for its kind, so code written
against the built-ins keeps working:

    try:
        fit = physid.identify(robot, "run.csv", constraints="consistent")
    except FileNotFoundError as e:      # physid.MissingFileError
        print("no such file:", e.filename)
    except ValueError as e:             # physid.InputError: an option, a file's content, an array
        print(e)
    except physid.Error as e:           # anything else physid reports (the solver)
        print(e)

Interrupting a call (Ctrl-C) raises `KeyboardInterrupt`, as everywhere in Python.
"""


class Error(Exception):
    """Base of every exception physid raises."""


class InputError(Error, ValueError):
    """An input physid cannot use: a keyword's value (named as the keyword), a file's content
    (named by file, field, sample or joint), an array's shape or a non-finite value."""


class MissingFileError(Error, FileNotFoundError):
    """A file or folder that was given does not exist (`filename` names it)."""


class SolverError(Error, RuntimeError):
    """The cone solver stopped without an answer (its status in the message)."""


class PhysidWarning(UserWarning):
    """A warning about the data or the answer (the CLI prints it as `warning: ...`)."""
