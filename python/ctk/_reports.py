"""JSON reports the toolkit writes, read back and checked: InputError naming the file and the key
unless the file is JSON of the format expected."""
from __future__ import annotations

import json
import os

from ._ctk import InputError


def input_error(file: str, key: str, what: str) -> InputError:
    error = InputError(f"{file}: {key}: {what}" if key else f"{file}: {what}")
    error.file, error.key = file, key
    return error


def read_report(file: str | os.PathLike, expected: str, required: dict[str, type] | None = None) -> dict:
    """The report in `file`, whose "format" must be `expected` and whose keys in `required` must
    hold values of the types given."""
    name = os.fspath(file)
    with open(file, encoding="utf-8") as f:
        try:
            report = json.load(f)
        except json.JSONDecodeError as e:
            raise input_error(name, "", f"not JSON: {e}") from None
    if not isinstance(report, dict) or report.get("format") != expected:
        raise input_error(name, "format", f'expected "{expected}"')
    for key, kind in (required or {}).items():
        if not isinstance(report.get(key), kind):
            raise input_error(name, key, f"expected a {kind.__name__}")
    return report
