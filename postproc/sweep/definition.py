"""The sweep definition: a namelist file with one ``&sweep`` group and one ``&input``
group per varied input (docs/sweep.md documents every variable).

The Fortran program ``airlaunch-sweep`` reads the same file and applies the same
rules (src/sweep/airlaunch_sweep_definition.f90); names of the varied scenario
variables are checked there, against the scenario readers themselves.
"""
from __future__ import annotations

import bisect
import dataclasses
import difflib
import math
import pathlib
import re
import sys

import f90nml

DESIGNS = ("lhs", "sobol", "grid")
DISTRIBUTIONS = ("uniform", "normal", "truncnorm", "list")
#: the airlaunch scene's six, then the line scene's own, then the touchdown speed of
#: both (airlaunch-sweep checks that worst_by is one of the base scene's summary variables)
WORST_BY = ("min_clearance_m", "min_line_clearance_m", "min_exit_clearance_m", "peak_line_tension_N",
            "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion", "max_end_tension_a_N",
            "max_end_tension_b_N", "line_recoil_speed_m_s", "final_tip_speed_m_s", "ground_speed_m_s")

SWEEP_VARS = ("name", "base", "output_dir", "design", "n_cases", "seed", "t_end", "keep_failed",
              "keep_worst", "worst_by", "keep_ids", "criteria", "progress_interval")
#: variables the sweep sets for every case (airlaunch_sweep_definition.f90, owned_by_sweep)
OWNED_BY_SWEEP = ("run%scene", "run%output", "run%trajectory")
OWNED_NOTE = ("the sweep sets it for every case (the scene is the base's scene; the output and "
              "whether there is one are the sweep's: summary mode, keep_failed, keep_worst)")

INPUT_VARS = ("name", "distribution", "lower", "upper", "mean", "std", "values", "levels", "units",
              "description")
FIXED_VARS = ("name", "value")
MAX_SEED = 2**31 - 1
#: Most cases a sweep may have (n_cases, or the points of a grid): airlaunch-sweep
#: counts cases in 32-bit integers, and a table of 1e7 cases takes about 5 s to draw.
MAX_CASES = 10_000_000


class DefinitionError(ValueError):
    """Bad sweep definition: the message is one line naming file, group and value."""


@dataclasses.dataclass(frozen=True)
class InputSpec:
    """One varied input: a scenario variable ``group%variable`` and its distribution."""

    name: str
    distribution: str
    lower: float = math.nan
    upper: float = math.nan
    mean: float = math.nan
    std: float = math.nan
    values: tuple = ()
    levels: int = 0
    units: str = ""
    description: str = ""

    @property
    def group(self) -> str:
        """Namelist group of the scenario variable."""
        return split_name(self.name)[0]

    @property
    def variable(self) -> str:
        """Variable name inside its group (without an element's index)."""
        return split_name(self.name)[1]

    @property
    def element(self) -> int:
        """The varied element i of a vector, ``group%variable(i)`` (0: the variable itself)."""
        return split_name(self.name)[2]

    def grid_size(self) -> int:
        """Number of grid levels of this input (design = 'grid')."""
        return len(self.values) if self.distribution == "list" else self.levels


@dataclasses.dataclass(frozen=True)
class SweepDefinition:
    """A validated sweep definition."""

    path: str
    name: str
    base: str
    output_dir: str
    design: str
    n_cases: int
    seed: int
    inputs: tuple
    t_end: float = 0.0
    keep_failed: bool = False
    keep_worst: int = 0
    worst_by: str = ""   # '' : the base scene's default
    keep_ids: tuple = ()
    criteria: str = ""
    progress_interval: float = 5.0
    fixed: tuple = ()

    @property
    def table_path(self) -> pathlib.Path:
        """Case table written by the table step."""
        return pathlib.Path(self.output_dir) / "table.nc"

    @property
    def summary_path(self) -> pathlib.Path:
        """Summary written by airlaunch-sweep."""
        return pathlib.Path(self.output_dir) / "summary.nc"

    @property
    def envelope_path(self) -> pathlib.Path:
        """Envelope written by the envelope step."""
        return pathlib.Path(self.output_dir) / "envelope.nc"

    @property
    def figure_dir(self) -> pathlib.Path:
        """Directory of the envelope figures."""
        return pathlib.Path(self.output_dir) / "figures"


def _suggest(name, allowed):
    close = difflib.get_close_matches(name, allowed, n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def show(value):
    """A value for a message: a very long integer is abbreviated."""
    try:
        text = str(value) if isinstance(value, int) and not isinstance(value, bool) else repr(value)
    except ValueError:   # an integer of more digits than Python converts
        return "an integer of more than 4000 digits"
    if len(text) > 40:
        return f"{text[:12]}...{text[-3:]} ({len(text)} digits)" if isinstance(value, int) else text[:40] + "..."
    return text


def to_float(value):
    """float(value), or None when the number does not fit a float (e.g. a 400-digit integer)."""
    try:
        return float(value)
    except OverflowError:
        return None


class NamelistText(str):
    """The text of a namelist file, with the encoding its bytes were decoded
    with (string lengths are counted in bytes of the file, as by Fortran)."""

    encoding = "utf-8"


def not_a_file(path: pathlib.Path) -> str:
    """Why `path`, which is not a regular file, cannot be read as one."""
    if path.is_dir():
        return "is a directory, not a file"
    if path.exists():
        return "is not a regular file (a device, FIFO or socket)"
    return "file does not exist"


def read_namelist_text(path, what):
    """The text of a namelist file; any byte is accepted (UTF-8, else Latin-1:
    a comment in any encoding just works)."""
    p = pathlib.Path(path)
    if not p.is_file():
        raise DefinitionError(f"{path}: {not_a_file(p)} (give the path of {what})")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise DefinitionError(f"{path}: cannot read the file: {exc.strerror or exc} (give the path of {what})") \
            from None
    try:
        text = NamelistText(data.decode("utf-8"))
    except UnicodeDecodeError:
        text = NamelistText(data.decode("latin-1"))
        text.encoding = "latin-1"
    return text


def _strip_comment(line):
    """A line without its '!' comment (quotes respected), as the Fortran readers do."""
    quote = ""
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = ""
        elif c in "'\"":
            quote = c
        elif c == "!":
            return line[:i]
    return line


def _is_name_start(c):
    return ("a" <= c <= "z") or ("A" <= c <= "Z")


def _is_name_char(c):
    return _is_name_start(c) or ("0" <= c <= "9") or c == "_"


_ASCII_LOWER = str.maketrans("ABCDEFGHIJKLMNOPQRSTUVWXYZ", "abcdefghijklmnopqrstuvwxyz")


def ascii_lower(s):
    """Lower case of the ASCII letters only, as Fortran's lower()."""
    return s.translate(_ASCII_LOWER)


def shown_text(s):
    """Text for a one-line message: control characters and line separators escaped."""
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in s)


#: Most values of a list variable (values, keep_ids): the Fortran reader's arrays
#: (max_list_items in src/io/airlaunch_namelist.f90).
MAX_LIST_ITEMS = 4096
INT_MIN, INT_MAX = -2**31, 2**31 - 1
#: Fortran's message for an integer that does not read as a default integer.
NOT_AN_INTEGER = f"is not an integer in [{-INT_MAX}, {INT_MAX}]"

#: Kind and most characters (bytes) of each variable, as the Fortran reader
#: declares it (src/sweep/airlaunch_sweep_definition.f90): kinds as nml_var's
#: "string", "integer", "real", "logical", "real_list", "integer_list".
DEFINITION_FORMS = {
    "sweep": {"name": ("string", 256), "base": ("string", 256), "output_dir": ("string", 256),
              "design": ("string", 256), "n_cases": ("integer", 0), "seed": ("integer", 0),
              "t_end": ("real", 0), "keep_failed": ("logical", 0), "keep_worst": ("integer", 0),
              "worst_by": ("string", 256), "keep_ids": ("integer_list", 0), "criteria": ("string", 256),
              "progress_interval": ("real", 0)},
    "input": {"name": ("string", 128), "distribution": ("string", 128), "lower": ("real", 0),
              "upper": ("real", 0), "mean": ("real", 0), "std": ("real", 0), "values": ("real_list", 0),
              "levels": ("integer", 0), "units": ("string", 128), "description": ("string", 1024)},
    "fixed": {"name": ("string", 128), "value": ("string", 1024)},
}

_REPEAT = re.compile(r"(\d+)\*(.*)", re.S)
_INTEGER = re.compile(r"[+-]?\d+")
_SIGNS = re.compile(r"[+-]+")


def _list_items(v):
    """The items of a list value (blanks and commas separate them), as Fortran's next_item."""
    return [x for x in re.split(r"[ ,]+", v) if x]


def _count_values(v):
    """(number of values of a list, repeat counts included, and whether an item
    cannot be a value: a repeat count < 1 or beyond a default integer, or a lone
    sign).  A bad repeat count counts 1, as in Fortran's count_values."""
    n, bad = 0, False
    for x in _list_items(v):
        star = x.find("*")
        k, rest = 1, x
        if star > 0:
            prefix, rest = x[:star], x[star + 1:]
            if _INTEGER.fullmatch(prefix) and len(prefix.lstrip("+-").lstrip("0")) <= 10 \
                    and 1 <= int(prefix) <= INT_MAX:
                k = int(prefix)
            else:
                bad = True
        if _SIGNS.fullmatch(rest):
            bad = True
        n += k
    return n, bad


def _has_null_value(v):
    """A null value in the value text v (one separator after the last value
    already dropped), as the Fortran reader's has_null_value: a comma with no
    value before it, a trailing comma, or a repeat count without a value;
    quotes respected."""
    seen, quote, i = False, "", 0
    while i < len(v):
        c = v[i]
        if quote:
            if c == quote:
                quote = ""
        elif c in "'\"":
            quote, seen = c, True
        elif c == ",":
            if not seen:
                return True
            seen = False
        elif c == "*":
            if i + 1 == len(v) or v[i + 1] in ", ":
                return True
        elif c != " ":
            seen = True
        i += 1
    return not seen


def _int_fits(text):
    """An integer literal that fits a default (32-bit) integer."""
    digits = text.lstrip("+-").lstrip("0")
    return len(digits) <= 10 and INT_MIN <= int(text) <= INT_MAX


def _check_form(path, item, kind, length, encoding):
    """Check one assignment's value text against its variable's kind, as the
    Fortran reader does (check_form and diagnose in src/io/airlaunch_namelist.f90):
    quoted strings no longer than the reader's variable, lists of at most
    MAX_LIST_ITEMS values, integers that fit 32 bits, numbers that are not a lone
    sign (a namelist parser reads '+' as an empty value)."""
    group, name, idx, line, v = item
    where = f"{path}:{line}: &{group}: "
    shown = shown_text(v)
    if not v.strip():
        raise DefinitionError(f"{where}'{name}{idx}' has no value (a namelist read would keep its default "
                              "silently): give a value, or leave the variable out")
    if _has_null_value(v):
        raise DefinitionError(f"{where}'{name}{idx}' = {shown} is not allowed: it has a null value (nothing "
                              "between separators, or a repeat count without a value), which a namelist read "
                              "skips, keeping the default silently; give every value")
    if kind in ("real_list", "integer_list"):
        n, bad = _count_values(v)
        what = "a list of real numbers" if kind == "real_list" else "a list of integers"
        if idx:
            m = re.fullmatch(r"\(([+-]?\d+)\)", idx)
            if m and not (len(m.group(1)) <= 10 and 1 <= int(m.group(1)) and int(m.group(1)) + n - 1
                          <= MAX_LIST_ITEMS):
                raise DefinitionError(f"{where}'{name}{idx}' = {shown} is not allowed ({name} holds at most "
                                      f"{MAX_LIST_ITEMS} values: indices 1 to {MAX_LIST_ITEMS})")
        elif n > MAX_LIST_ITEMS:
            raise DefinitionError(f"{where}'{name}' has {n} values; at most {MAX_LIST_ITEMS} are allowed")
        if bad:
            raise DefinitionError(f"{where}variable '{name}' = {shown} is not {what}")
        return
    if kind == "string":
        m = _REPEAT.fullmatch(v)
        body = m.group(2) if m else v
        if not body:
            return
        if body[0] not in "'\"" or (m and m.group(1).lstrip("0") != "1"):
            raise DefinitionError(f"{where}variable '{name}' = {shown} is not a quoted string")
        n = len(body.encode(encoding, "replace")) - 2
        if length and n > length:
            # output_dir: also say that the directory is not usable (as the table
            # step says of a directory it cannot make)
            usable = f" (output_dir = {shown} is not usable)" if (group, name) == ("sweep", "output_dir") else ""
            raise DefinitionError(f"{where}'{name}' is {n} characters long; at most {length} are allowed{usable}")
        return
    expected = {"integer": f"an integer in [{-INT_MAX}, {INT_MAX}]", "real": "a real number",
                "logical": ".true. or .false."}.get(kind)
    if expected is None or not v:
        return
    n, bad = _count_values(v)
    m = _REPEAT.fullmatch(v)
    body = m.group(2) if m else v
    out_of_range = (kind == "integer" and name != "n_cases"   # n_cases > 1e7: its own message
                    and _INTEGER.fullmatch(body) is not None and not _int_fits(body))
    if n != 1 or bad or _SIGNS.fullmatch(body) or out_of_range:
        raise DefinitionError(f"{where}variable '{name}' = {shown} is not {expected}")


def _check_list_order(path, item, before):
    """The assignments of a list variable in one group fill it in order, without
    gaps: the whole list first (`values = a, b`), then elements one value each,
    `values(3) = c`, the next index each time (`before` values are set so far).
    f90nml would leave a gap as None or drop values (`values(3) = 0.5, 0.7`),
    airlaunch-sweep would count the leading values only or refuse the read:
    both steps refuse these alike (check_list_order in src/io/airlaunch_namelist.f90)."""
    group, name, idx, line, v = item
    nxt = before + 1
    if not idx:
        ok = nxt == 1
    else:
        m = re.fullmatch(r"\(([+-]?\d+)\)", idx)
        ok = m is not None and len(m.group(1)) <= 10 and int(m.group(1)) == nxt and _count_values(v)[0] == 1
    if not ok:
        raise DefinitionError(f"{path}:{line}: &{group}: '{name}{idx}' = {shown_text(v)} is not allowed: the elements "
                              f"of {name} are given one value each, in order and without gaps ({name}({nxt}) is "
                              f"next), or as the whole list first ({name} = a, b, ...)")


def check_namelist_text(text, path, forms=None):
    """Scan the raw text of a namelist like the Fortran readers
    (src/io/airlaunch_namelist.f90) and raise DefinitionError for what a
    namelist parser would let through silently or misreport: text outside a
    group, a string not closed on its line, a group not closed (with /; '$end'
    does not close a group), a variable assigned twice in one group (a namelist
    keeps the last value; x(1) and x(2) are different variables), and, for the
    variables of `forms` ({group: {variable: (kind, most characters)}}), a value
    not of the variable's form (see _check_form).  Any value of more than
    MAX_LIST_ITEMS values is refused before a parser expands it."""
    encoding = getattr(text, "encoding", "utf-8")
    parts, starts, pos = [], [], 0
    for line in text.split("\n"):
        line = _strip_comment(line.replace("\r", " ").replace("\t", " ")).rstrip()
        starts.append(pos)
        parts.append(line + " ")
        pos += len(line) + 1
    t = "".join(parts)
    n = len(t)

    def line_of(i):
        return bisect.bisect_right(starts, i)

    in_group, group, gline, n_groups = False, "", 0, 0
    items = []    # (group number, (group, name, index, line, value))
    item = None   # (name, index, line, start of the value)

    def close_item(end):
        nonlocal item
        if item is None:
            return
        name, idx, line, vstart = item
        value = t[vstart:end].strip(" ")
        if value.endswith(","):
            value = value[:-1].rstrip(" ")
        items.append((n_groups, (group, name, idx, line, value)))
        item = None

    i = 0
    while i < n:
        c = t[i]
        if not in_group:
            if c in "&$":
                j = i + 1
                while j < n and _is_name_char(t[j]):
                    j += 1
                name = ascii_lower(t[i + 1:j])
                if name != "end":
                    in_group, group, gline, item = True, name, line_of(i), None
                    n_groups += 1
                i = j
                continue
            if c != " ":
                raise DefinitionError(f"{path}:{line_of(i)}: text outside a namelist group: "
                                      f"'{shown_text(t[i:i + 21].rstrip(' '))}' (groups start with &name and "
                                      "end with /)")
            i += 1
            continue
        if c in "'\"":
            j = t.find(c, i + 1)
            if j < 0 or line_of(j) != line_of(i):
                shown = t[i:starts[line_of(i) - 1] + len(parts[line_of(i) - 1])].rstrip()
                raise DefinitionError(f"{path}:{line_of(i)}: &{group}: unterminated string "
                                      f"{shown_text(shown[:40])} (a quoted value must end with its {c} on the "
                                      "same line)")
            i = j + 1
            continue
        if c == "/":
            close_item(i)
            in_group = False
            i += 1
            continue
        if c == "&":
            if t[i + 1:i + 4].lower() == "end":
                close_item(i)
                in_group = False
                i += 4
                continue
            raise DefinitionError(f"{path}:{line_of(i)}: group &{group} is not closed with / before the next group")
        if _is_name_start(c) and (i == 0 or t[i - 1] in " ,&"):
            j = i
            while j < n and (_is_name_char(t[j]) or t[j] == "%"):
                j += 1
            k, idx = j, ""
            if k < n and t[k] == "(":
                close = t.find(")", k)
                k = n if close < 0 else close + 1
                idx = ascii_lower(t[j:k].replace(" ", ""))
            while k < n and t[k] == " ":
                k += 1
            if k < n and t[k] == "=":
                close_item(i)
                item = (ascii_lower(t[i:j]), idx, line_of(i), k + 1)
                i = k + 1
                continue
            i = j
            continue
        i += 1
    if in_group:
        raise DefinitionError(f"{path}:{gline}: group &{group} is not closed (end it with /)")

    seen, filled = {}, {}
    for number, it in items:
        grp, name, idx, line, value = it
        kind, length = (forms or {}).get(grp, {}).get(name, (None, 0))
        if kind is not None:
            _check_form(path, it, kind, length, encoding)
        elif _count_values(value)[0] > MAX_LIST_ITEMS:   # before a parser expands it
            raise DefinitionError(f"{path}:{line}: &{grp}: '{name}{idx}' has {_count_values(value)[0]} values; "
                                  f"at most {MAX_LIST_ITEMS} are allowed")
        key = (number, name, idx)
        if key in seen:
            first_line, first_value = seen[key]
            raise DefinitionError(f"{path}:{line}: &{grp}: '{name}{idx}' = {shown_text(value)} is assigned a second "
                                  f"time (first at line {first_line}: {shown_text(first_value)}); a namelist would "
                                  "keep the last value silently, so give it once")
        seen[key] = (line, value)
        if kind in ("real_list", "integer_list"):
            _check_list_order(path, it, filled.get((number, name), 0))
            filled[(number, name)] = filled.get((number, name), 0) + _count_values(value)[0]


def _groups(nml, group):
    """All occurrences of a group (f90nml gives one Namelist or a Cogroup list)."""
    if group not in nml:
        return []
    value = nml[group]
    return list(value) if isinstance(value, list) else [value]


def _check_names(where, values, allowed, kind="variable"):
    for key in values:
        if key not in allowed:
            raise DefinitionError(f"{where}unknown {kind} '{key}'{_suggest(key, allowed)} "
                                  f"(allowed: {', '.join(allowed)})")


def _real(where, group_vars, key, required=False):
    if key not in group_vars or group_vars[key] is None:
        if required:
            raise DefinitionError(f"{where}missing required value {key}")
        return math.nan
    value = group_vars[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DefinitionError(f"{where}{key} = {value!r} is not a real number")
    number = to_float(value)
    if number is None or not math.isfinite(number):
        raise DefinitionError(f"{where}{key} = {show(value)} is not allowed (must be a finite real number, "
                              f"|x| <= {sys.float_info.max:.4g})")
    return number


def _int(where, group_vars, key, default=None):
    if key not in group_vars or group_vars[key] is None:
        if default is None:
            raise DefinitionError(f"{where}missing required value {key}")
        return default
    value = group_vars[key]
    if isinstance(value, bool) or not isinstance(value, int):
        raise DefinitionError(f"{where}{key} = {value!r} is not an integer")
    return value


def _str(where, group_vars, key, default=None):
    if key not in group_vars or group_vars[key] is None:
        if default is None:
            raise DefinitionError(f"{where}missing required value {key}")
        return default
    value = group_vars[key]
    if not isinstance(value, str):
        raise DefinitionError(f"{where}{key} = {value!r} is not a quoted string")
    # trailing blanks mean nothing to Fortran (blank-padded strings); leading
    # blanks are part of the value, as for airlaunch-sweep
    return value.rstrip()


def _choice(where, key, value, choices):
    if value not in choices:
        raise DefinitionError(f"{where}{key} = '{value}' is not allowed (one of: {', '.join(choices)})")


def _as_list(value):
    if value is None:
        return []
    return list(value) if isinstance(value, list) else [value]


_NAME = re.compile(r"([a-z0-9_]+)%([a-z0-9_]+)(?:\(([0-9]{1,9})\))?")


def _valid_name(name):
    """group%variable of ASCII letters, digits and '_', or group%variable(i)
    for element i of a vector, i of 1 to 9 digits (valid_name in the Fortran
    reader)."""
    return _NAME.fullmatch(name) is not None


def split_name(name):
    """(group, variable, element) of a valid name; element 0: no index."""
    m = _NAME.fullmatch(name)
    return m.group(1), m.group(2), int(m.group(3)) if m.group(3) is not None else 0


def _normal_name(where, name):
    """The name with its index without leading zeros ('wind(01)' is 'wind(1)'); index 0 refused."""
    group, variable, element = split_name(name)
    if "(" in name and element == 0:
        raise DefinitionError(f"{where}name = '{name}' is not allowed (an element index starts at 1: "
                              "group%variable(1), (2), ...)")
    return f"{group}%{variable}" + (f"({element})" if element else "")


def _read_fixed(path, index, group_vars, varied):
    """Validate one &fixed group: (name, value text)."""
    where = f"{path}: &fixed #{index}: "
    _check_names(where, group_vars, FIXED_VARS)
    name = ascii_lower(_str(where, group_vars, "name"))
    if not _valid_name(name):
        raise DefinitionError(f"{where}name = '{name}' is not allowed (write group%variable, or "
                              "group%variable(i) for element i of a vector, e.g. 'flight%trim_mode', "
                              "'line%wind(1)')")
    name = _normal_name(where, name)
    if "%".join(split_name(name)[:2]) in OWNED_BY_SWEEP:
        raise DefinitionError(f"{where}name = '{name}' is not allowed: {OWNED_NOTE}")
    where = f"{path}: &fixed #{index} '{name}': "
    value = _str(where, group_vars, "value", "")
    if not value:
        raise DefinitionError(f"{where}missing required value value (the value as namelist text: a number, "
                              "or a string with its own quotes)")
    if name in varied:
        raise DefinitionError(f"{where}{name} is also a varied input")
    return name, value


def _read_input(path, index, group_vars, design):
    """Validate one &input group (of a sweep of the given design)."""
    where = f"{path}: &input #{index}: "
    _check_names(where, group_vars, INPUT_VARS)
    name = ascii_lower(_str(where, group_vars, "name"))
    where = f"{path}: &input #{index} '{name}': "
    if not _valid_name(name):
        raise DefinitionError(f"{where}name = '{name}' is not allowed (write group%variable, or "
                              "group%variable(i) for element i of a vector, e.g. 'bay%release_time', "
                              "'line%wind(1)')")
    name = _normal_name(where, name)
    where = f"{path}: &input #{index} '{name}': "
    if "%".join(split_name(name)[:2]) in OWNED_BY_SWEEP:
        raise DefinitionError(f"{where}name = '{name}' is not allowed: {OWNED_NOTE}")
    dist = ascii_lower(_str(where, group_vars, "distribution"))
    _choice(where, "distribution", dist, DISTRIBUTIONS)
    spec = dict(name=name, distribution=dist, units=_str(where, group_vars, "units", ""),
                description=_str(where, group_vars, "description", ""))
    if "levels" in group_vars and design != "grid":
        raise DefinitionError(f"{where}levels is not used by design = '{design}' (only by design = 'grid')")
    if "levels" in group_vars and dist == "list":
        raise DefinitionError(f"{where}levels is not used by distribution = 'list' (a grid takes the list's "
                              "values; only by uniform, normal and truncnorm)")
    levels = _int(where, group_vars, "levels", 0)
    if levels < 0:
        raise DefinitionError(f"{where}levels = {show(levels)} is not allowed (must be >= 1)")
    spec["levels"] = levels
    if dist in ("uniform", "truncnorm"):
        lower = _real(where, group_vars, "lower", required=True)
        upper = _real(where, group_vars, "upper", required=True)
        if not upper > lower:
            raise DefinitionError(f"{where}upper = {upper:g} is not allowed (must be > lower = {lower:g}: "
                                  "reversed or empty bounds)")
        spec.update(lower=lower, upper=upper)
    if dist in ("normal", "truncnorm"):
        mean = _real(where, group_vars, "mean", required=True)
        std = _real(where, group_vars, "std", required=True)
        if not std > 0:
            raise DefinitionError(f"{where}std = {std:g} is not allowed (must be > 0)")
        spec.update(mean=mean, std=std)
    if dist == "list":
        raw = _as_list(group_vars.get("values"))
        if not raw:
            raise DefinitionError(f"{where}missing required value values (the list of values)")
        values = []
        for v in raw:
            number = None if isinstance(v, bool) or not isinstance(v, (int, float)) else to_float(v)
            if number is None or not math.isfinite(number):
                raise DefinitionError(f"{where}values: {show(v)} is not a finite real number "
                                      f"(|x| <= {sys.float_info.max:.4g})")
            values.append(number)
        spec["values"] = tuple(values)
    else:
        for key in ("values",):
            if key in group_vars:
                raise DefinitionError(f"{where}{key} is only used by distribution = 'list'")
    for key, dists in (("lower", ("uniform", "truncnorm")), ("upper", ("uniform", "truncnorm")),
                       ("mean", ("normal", "truncnorm")), ("std", ("normal", "truncnorm"))):
        if key in group_vars and dist not in dists:
            raise DefinitionError(f"{where}{key} is not used by distribution = '{dist}' "
                                  f"(only by {' and '.join(dists)})")
    return InputSpec(**spec)


def _utf8_path(where, key, value, encoding):
    """Refuse a path of a file that is not UTF-8 (read as Latin-1) with bytes
    beyond ASCII: airlaunch-sweep takes its bytes as they are, the Python
    steps would name another file (their UTF-8 encoding of the Latin-1 text),
    and netCDF takes UTF-8 paths only (found by an audit: the table went to
    'lat\xc3\xbfdir', the cases looked for it in 'lat\xffdir')."""
    if encoding != "utf-8" and not value.isascii():
        shown = value.encode(encoding, "replace").decode("ascii", "backslashreplace")
        raise DefinitionError(f"{where}{key} = '{shown}' is not allowed: the file is not UTF-8 and this path holds "
                              "other bytes, which airlaunch-sweep and the Python steps would take for different "
                              "files (write the file in UTF-8, or keep its paths ASCII)")


def parse_definition(text, path="<sweep>"):
    """Validate the text of a sweep definition; return a SweepDefinition."""
    check_namelist_text(text, path, DEFINITION_FORMS)
    try:
        nml = f90nml.reads(text)
    except Exception as exc:  # f90nml raises several exception types
        raise DefinitionError(f"{path}: cannot read the namelist: {_first_line(exc)}") from None
    _check_names(f"{path}: ", list(nml.keys()), ("sweep", "input", "fixed"), kind="group")
    sweeps = _groups(nml, "sweep")
    if len(sweeps) != 1:
        raise DefinitionError(f"{path}: the group &sweep must appear once (found {len(sweeps)})")
    sweep = sweeps[0]
    where = f"{path}: &sweep: "
    _check_names(where, sweep, SWEEP_VARS)
    design = ascii_lower(_str(where, sweep, "design"))
    _choice(where, "design", design, DESIGNS)
    base = _str(where, sweep, "base")
    if not base:
        raise DefinitionError(f"{where}base = '' is not allowed (the base scenario file)")
    # '' as absent: the file's stem (airlaunch-sweep's rule too)
    name = _str(where, sweep, "name", "") or pathlib.Path(path).stem
    output_dir = _str(where, sweep, "output_dir", f"output/sweep_{name}")
    if not output_dir:
        raise DefinitionError(f"{where}output_dir = '' is not allowed (a directory, e.g. 'output/sweep_{name}')")
    encoding = getattr(text, "encoding", "utf-8")
    for key, value in (("base", base), ("output_dir", output_dir), ("criteria", _str(where, sweep, "criteria", ""))):
        _utf8_path(where, key, value, encoding)
    groups = _groups(nml, "input")
    if not groups:
        raise DefinitionError(f"{path}: no &input group (at least one varied input is needed)")
    inputs = tuple(_read_input(path, i + 1, g, design) for i, g in enumerate(groups))
    names = [s.name for s in inputs]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise DefinitionError(f"{path}: &input #{i + 1} '{n}': the input is varied twice")
    fixed = tuple(_read_fixed(path, i + 1, g, names) for i, g in enumerate(_groups(nml, "fixed")))
    fixed_names = [n for n, _ in fixed]
    for i, n in enumerate(fixed_names):
        if n in fixed_names[:i]:
            raise DefinitionError(f"{path}: &fixed #{i + 1} '{n}': {n} is fixed twice")
    if design == "grid":
        for i, s in enumerate(inputs):
            if s.grid_size() < 1:
                raise DefinitionError(f"{path}: &input #{i + 1} '{s.name}': missing required value levels "
                                      "(design = 'grid' needs levels >= 1 or a list of values)")
        n_grid = math.prod(s.grid_size() for s in inputs)
        if n_grid > MAX_CASES:
            sizes = " x ".join(show(s.grid_size()) for s in inputs)
            raise DefinitionError(f"{path}: &input: levels = {sizes} is not allowed (the grid would have "
                                  f"{show(n_grid)} points; at most {MAX_CASES} cases)")
        n_cases = _int(where, sweep, "n_cases", n_grid)
        if n_cases != n_grid:
            raise DefinitionError(f"{where}n_cases = {show(n_cases)} is not allowed (the grid has "
                                  f"{n_grid} points: the product of the levels)")
        seed = _int(where, sweep, "seed", 0)
    else:
        n_cases = _int(where, sweep, "n_cases")
        seed = _int(where, sweep, "seed")
    if n_cases < 1:
        raise DefinitionError(f"{where}n_cases = {n_cases} is not allowed (must be >= 1: zero cases)")
    if n_cases > MAX_CASES:
        raise DefinitionError(f"{where}n_cases = {show(n_cases)} is not allowed (at most {MAX_CASES} cases: "
                              "airlaunch-sweep counts cases in 32-bit integers)")
    if not 0 <= seed <= MAX_SEED:
        raise DefinitionError(f"{where}seed = {show(seed)} is not allowed (must be in [0, {MAX_SEED}])")
    t_end = _real(where, sweep, "t_end")
    t_end = 0.0 if math.isnan(t_end) else t_end
    if t_end < 0:
        raise DefinitionError(f"{where}t_end = {t_end:g} is not allowed (must be > 0 s, or 0 for the "
                              "base scenario's)")
    # &sweep t_end sets run%t_end for every case: not also an &input or &fixed (airlaunch-sweep alike)
    if t_end > 0:
        for i, s in enumerate(inputs):
            if s.name == "run%t_end":
                raise DefinitionError(f"{path}: &input #{i + 1} 'run%t_end': run%t_end is also set by &sweep "
                                      "t_end (vary it here and leave &sweep t_end out, or fix it there)")
        for i, (n, _) in enumerate(fixed):
            if n == "run%t_end":
                raise DefinitionError(f"{path}: &fixed #{i + 1} 'run%t_end': run%t_end is also set by &sweep "
                                      "t_end (give it once: &sweep t_end)")
    keep_failed = sweep.get("keep_failed", False)
    if not isinstance(keep_failed, bool):
        raise DefinitionError(f"{where}keep_failed = {keep_failed!r} is not .true. or .false.")
    keep_worst = _int(where, sweep, "keep_worst", 0)
    if keep_worst < 0:
        raise DefinitionError(f"{where}keep_worst = {show(keep_worst)} is not allowed (must be >= 0)")
    # not set: the base scene's default (airlaunch-sweep: min_clearance_m, a line scene's peak_line_tension_N)
    worst_by = _str(where, sweep, "worst_by", "")
    if worst_by:
        _choice(where, "worst_by", worst_by, WORST_BY)
    keep_ids = []
    for v in _as_list(sweep.get("keep_ids")):
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < n_cases:
            raise DefinitionError(f"{where}keep_ids: {show(v)} is not allowed (case ids are integers in "
                                  f"[0, {n_cases - 1}])")
        keep_ids.append(v)
    progress = _real(where, sweep, "progress_interval")
    progress = 5.0 if math.isnan(progress) else progress
    if not progress > 0:
        raise DefinitionError(f"{where}progress_interval = {progress:g} is not allowed (must be > 0 s)")
    return SweepDefinition(path=str(path), name=name, base=base, output_dir=output_dir, design=design,
                           n_cases=n_cases, seed=seed, inputs=inputs, t_end=t_end,
                           keep_failed=keep_failed, keep_worst=keep_worst, worst_by=worst_by,
                           keep_ids=tuple(keep_ids), criteria=_str(where, sweep, "criteria", ""),
                           progress_interval=progress, fixed=fixed)


def check_base(defn):
    """The base scenario must be an existing regular file (docs/sweep.md: "an
    existing, valid scenario"; whether it is valid, airlaunch-sweep --check
    decides). A relative path is taken from the current directory, as
    airlaunch-sweep takes it (src/sweep/airlaunch_sweep_definition.f90)."""
    base = pathlib.Path(defn.base)
    try:
        why = None if base.is_file() else ("is a directory" if base.is_dir() else
                                            "is not a regular file" if base.exists() else "does not exist")
    except OSError as exc:
        why = f"cannot be read ({exc.strerror or exc})"
    if why:
        raise DefinitionError(f"{defn.path}: &sweep: base = '{shown_text(defn.base)}' is not allowed: the file "
                              f"{why} (allowed: an existing regular file, the base scenario; a relative path is "
                              "taken from the current directory)")


def _first_line(exc):
    """The first line of an exception's message (messages must be one line)."""
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__


def read_definition(path):
    """Read and validate a sweep definition file."""
    return parse_definition(read_namelist_text(path, "a sweep definition"), str(path))
