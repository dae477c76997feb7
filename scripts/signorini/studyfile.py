"""Validating YAML study files: the StudyError exception and the checks of keys, numbers, names
and solver options. Every message names the file and the key at fault (`where`)."""
import math
import os
import re

import yaml

from .paths import ROOT

NAME_RE = r"[A-Za-z0-9._\-]+"  # file-name-safe names


class StudyError(Exception):
    """An error in the study file, a run or its output; the message names the culprit."""


def read_yaml(path):
    """The parsed YAML of a study file; StudyError if it cannot be read or parsed."""
    try:
        with open(path) as fh:
            return yaml.safe_load(fh)
    except OSError as exc:
        raise StudyError(f"{path}: cannot read the study file ({exc.strerror})") from exc
    except yaml.YAMLError as exc:
        raise StudyError(f"{path}: invalid YAML ({exc})") from exc


def check_keys(mapping, allowed, required, where):
    """Return `mapping`; StudyError if it is not a dict, lacks a required key or has an unknown one."""
    if not isinstance(mapping, dict):
        raise StudyError(f"{where}: expected a mapping, got {type(mapping).__name__}")
    for key in required:
        if key not in mapping:
            raise StudyError(f"{where}: missing required key '{key}'")
    for key in mapping:
        if key not in allowed:
            raise StudyError(f"{where}: unknown key '{key}' (allowed: {', '.join(allowed)})")
    return mapping


def number(value, where, integer=False):
    """Return `value` if it is an int (or, unless `integer`, a float); booleans are refused."""
    kinds = (int,) if integer else (int, float)
    if isinstance(value, bool) or not isinstance(value, kinds):
        raise StudyError(f"{where}: expected {'an integer' if integer else 'a number'}, got {value!r}")
    return value


def integer(value, where, minimum):
    """An integer >= minimum (booleans are refused)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise StudyError(f"{where}: expected an integer >= {minimum}, got {value!r}")
    return value


def positive(value, where):
    """A number > 0; numeric strings such as '1e-2' (YAML 1.1 reads them as text) are accepted."""
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise StudyError(f"{where}: expected a number > 0, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0 \
            or not math.isfinite(value):
        raise StudyError(f"{where}: expected a finite number > 0, got {value!r}")
    return float(value)


def string(value, where):
    """A string (numbers are accepted and converted)."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise StudyError(f"{where}: expected a string, got {value!r}")
    return str(value)


def safe_name(value, where):
    """A file-name-safe name."""
    if not isinstance(value, str) or not re.fullmatch(NAME_RE, value):
        raise StudyError(f"{where}: {value!r} is not a name of letters, digits, '.', '_', '-'")
    return value


def name_list(value, where):
    """A non-empty list of distinct strings (attribute names)."""
    if (not isinstance(value, list) or not value or not all(isinstance(n, str) for n in value)
            or len(set(value)) != len(value)):
        raise StudyError(f"{where}: expected a non-empty list of distinct attribute names")
    return list(value)


def safe_label(label):
    """File-name stem of a series label: characters other than [A-Za-z0-9.-] become '_'."""
    return re.sub(r"[^A-Za-z0-9.\-]", "_", label)


def option_value(value, where):
    """PETSc command-line text of an option value: booleans -> true/false, numbers via repr."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return value
    raise StudyError(f"{where}: option value must be a string, number or boolean, got {value!r}")


def options(mapping, where, reserved=("output",), name_key=False):
    """Validate an options mapping; return {key: value text}, keys without the leading dash.

    The options in `reserved` are set by the driver and refused; the message names `where`, or
    `where.key` with `name_key`.
    """
    if mapping is None:
        return {}
    if not isinstance(mapping, dict):
        raise StudyError(f"{where}: expected a mapping of options, got {type(mapping).__name__}")
    out = {}
    for key, value in mapping.items():
        if not isinstance(key, str):  # YAML 1.1 reads on/off/yes/no as booleans, 1 as a number
            raise StudyError(f"{where}: option key {key!r} was read by YAML as "
                             f"{type(key).__name__}; quote it")
        if not re.fullmatch(r"[A-Za-z0-9_]+", key):
            raise StudyError(f"{where}: invalid option key {key!r} (give it without the dash)")
        if key in reserved:
            at = f"{where}.{key}" if name_key else where
            raise StudyError(f"{at}: option '{key}' is set by the driver, remove it")
        out[key] = option_value(value, f"{where}.{key}")
    return out


def options_file(value, where):
    """An options file relative to ROOT (or absolute) that exists; None stays None."""
    if value is None:
        return None
    if not isinstance(value, str) or not os.path.isfile(os.path.join(ROOT, value)):
        raise StudyError(f"{where}: no such file {value!r} (relative paths are relative to {ROOT})")
    return value
