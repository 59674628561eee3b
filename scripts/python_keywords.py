"""The Python package's keyword documentation, generated from the CLI's own help (`physid
keywords`): one file per function in python/keywords/, included in the function's docstring by
the extension (`#[doc = include_str!(…)]`). Every keyword of every function is documented: by
its CLI flag's help (flag: the keyword with dashes), or, for a keyword the CLI has no flag for,
by the text below (PYTHON_ONLY).

The same text closes each function's docstring in the type stubs (python/physid/_physid.pyi),
after a line "Keywords:", for editors that read the stubs.

By default it checks that python/keywords/ and the stubs are current; $PHYSID_BIN is the built
physid and $PHYSID_PYTHON a folder holding the built package, as scripts/test.sh makes them.
"""
import inspect
import json
import os
import re
import subprocess
import sys
import textwrap

from physid_common import ROOT, arguments, physid_bin

# Python function -> the CLI command whose flags it takes.
COMMANDS = {
    "identify": "identify",
    "load": "identify",
    "diagnose": "diagnose",
    "simulate": "simulate",
    "excite": "excite",
    "score_motion": "excite",
    "experiment": "experiment",
    "sweep": "sweep",
    "compare": "compare",
    "Robot": "model",
    "simulate_floating": "simulate-floating",
    "identify_floating": "identify-floating",
    "FloatingRobot": "identify-floating",
}

# A keyword whose flag is its negation (python/src/errors.rs, keyword(), names flags as keywords
# in messages with its own list of exceptions).
NEGATED = {"description_information": "no-description-information", "check": "no-check"}

# A keyword whose flag is named otherwise.
FLAG = {"package_dirs": "package-dir"}

# Keywords that take runs: a path, a physid.Data held in memory, or a list of them.
RUNS = {"data", "validate_data", "baseline_data"}
# Functions over a floating robot: its log is one CSV path and its robot a path or "cheetah3"
# (no physid.Robot, which is a fixed-base robot), so the texts above do not apply.
FLOATING = {"simulate_floating", "identify_floating", "FloatingRobot"}

# Keywords the CLI has no flag for (Python's own), or whose Python form differs (these come
# first).
PYTHON_FIRST = {
    "sensors": "The sensors' noise and what they log: a dict over the default sensors' fields (torque_noise, force_noise, gyro_noise, gyro_bias, velocity_noise, velocity_bias, tilt_noise, position_noise, accel_noise, accel_bias, encoder_step; velocities, forces, contacts, accelerometer: True/False), or \"exact\" for noise-free sensors logging everything.",
    "robot": "The robot: a physid.Robot (as returned by physid.Robot), or \"cheetah3\" (the built-in leg), a URDF or a robot TOML path.",
}
FLOATING_ROBOT = "The robot: a physid.FloatingRobot (as loaded, rotors and all), or \"cheetah3\" (the built-in quadruped), a floating URDF or its sidecar TOML path. Default: cheetah3."
PYTHON_ONLY = {
    "baseline": "A results folder to compare against.",
    "scenario": "A scenario TOML file.",
    "sweep": "A sweep TOML file (docs/sweeps.md).",
    "result": "A results folder (of physid experiment or physid sweep).",
    "out": "Where to write (never over an input).",
    "progress": "A callable told the progress (simulate: the fraction of the run done; excite: the fraction of the design's evaluations done; experiment, sweep: done, total), on the calling thread, in order; an exception in it stops the work.",
    "threads": "Worker threads (default: all cores); the results do not depend on it.",
    "package_dirs": "Folders that package:// mesh paths of a URDF resolve against (a path or a list).",
}


def cli_flags(binary):
    out = subprocess.run([binary, "keywords"], capture_output=True, text=True, check=True)
    return {command: {f["flag"]: f for f in flags} for command, flags in json.loads(out.stdout).items()}


def keywords(function):
    """The keyword arguments of a function (or a class's constructor) of the built package."""
    sig = inspect.signature(function)
    return [p.name for p in sig.parameters.values() if p.name not in ("self", "py")]


def in_keywords(text):
    """The CLI's flags in `text` (`--baseline-data`) named as keywords (`baseline_data`)."""
    return re.sub(r"(?<![\w-])--([a-z][a-z0-9-]*)", lambda m: m.group(1).replace("-", "_"), text)


def described(flag, negated=False):
    """A keyword's text from its CLI flag's help: the help, allowed values, default."""
    text = " ".join(flag["help"].split())
    if text and not text.endswith("."):
        text += "."
    if negated:
        return f"True unless: {text[0].lower()}{text[1:]} (False is the CLI's --{flag['flag']}.)"
    if flag["values"] and flag["values"] != ["true", "false"]:
        text += f" One of: {', '.join(flag['values'])}."
    if flag["default"] and flag["default"] != ["false"]:
        text += f" Default: {', '.join(flag['default'])}."
    return text


def document(name, flags):
    lines = ["", "Keywords:", ""]
    for keyword in keywords(getattr(physid, name)):
        flag = flags.get(NEGATED.get(keyword) or FLAG.get(keyword) or keyword.replace("_", "-"))
        if keyword in PYTHON_FIRST and (name not in FLOATING or keyword == "sensors"):
            text = PYTHON_FIRST[keyword]
        elif keyword == "robot" and name in FLOATING and name != "FloatingRobot":
            text = FLOATING_ROBOT
        elif flag:
            text = in_keywords(described(flag, negated=keyword in NEGATED))
        elif keyword in PYTHON_ONLY:
            text = PYTHON_ONLY[keyword]
        else:
            sys.exit(f"{name}: keyword '{keyword}' has no CLI flag and no text in PYTHON_ONLY")
        if (keyword in RUNS and name not in FLOATING) or (keyword == "validate" and name == "diagnose"):
            text += " Paths, physid.Data held in memory, or a list of them."
        lines += textwrap.wrap(f"{keyword}: {text}", width=92, subsequent_indent="    ")
    return "\n".join(lines) + "\n"


def in_stub(stub, name, text):
    """`stub` (the .pyi text) with the docstring of function `name` (a class: its __init__)
    ending in `text`, replacing what followed its "Keywords:" line."""
    at = stub.index(f"\nclass {name}:") if name[0].isupper() else stub.index(f"\ndef {name}(")
    if name[0].isupper():
        at = stub.index("    def __init__(", at)
    indent = " " * (8 if name[0].isupper() else 4)
    opening = stub.index(f'{indent}"""', stub.index(":\n", stub.index(") ->", at)))
    closing = stub.index('"""', opening + len(indent) + 3)
    body = stub[opening + len(indent) + 3:closing].split(f"\n\n{indent}Keywords:")[0].rstrip()
    keywords = textwrap.indent(text.strip("\n").split("Keywords:", 1)[1].strip("\n"), indent)
    doc = f"{body}\n\n{indent}Keywords:\n\n{keywords}\n{indent}"
    return stub[:opening + len(indent) + 3] + doc + stub[closing:]


if __name__ == "__main__":
    args = arguments(__doc__, (["--write"], dict(
        action="store_true", help="write python/keywords/ and the stubs instead of checking them")))
    package = os.environ.get("PHYSID_PYTHON")
    if package:
        sys.path.insert(0, package)
    import physid  # noqa: E402

    flags = cli_flags(physid_bin(args.physid))
    folder = os.path.join(ROOT, "python", "keywords")
    stale = []
    stub_path = os.path.join(ROOT, "python", "physid", "_physid.pyi")
    stub = open(stub_path).read()
    for name, command in COMMANDS.items():
        text = document(name, flags[command])
        stub = in_stub(stub, name, text)
        path = os.path.join(folder, f"{name}.txt")
        if args.write:
            os.makedirs(folder, exist_ok=True)
            with open(path, "w") as f:
                f.write(text)
        elif not os.path.exists(path) or open(path).read() != text:
            stale.append(path)
    if args.write:
        with open(stub_path, "w") as f:
            f.write(stub)
    elif open(stub_path).read() != stub:
        stale.append(stub_path)
    if stale:
        sys.exit(f"stale keyword documentation (python scripts/python_keywords.py --write): {stale}")
    print(f"python keywords: {len(COMMANDS)} passed, 0 failed")
