"""The argument checks of nbv's functions, one per kind of argument.

The compiled module takes typed arguments (a float, an int, a str, an nbv.OccupancyMap, ...)
and pybind11 converts them; a value of another type would meet pybind11's TypeError, which
names every argument's C++ type and prints the arrays given in full. So each function users call
is a Python function whose signature holds the parameters and their defaults, and whose
annotations say the kind of each: `checked` converts every argument by its kind before the call,
and names the one it cannot use, e.g. "Decider.evaluate: seed = -3 is not a non-negative
int". Arrays are not checked here: the compiled module reads them and names their shape or dtype.
"""

import inspect
import numbers
import os

import numpy as np

from ._nbv import InvalidArgument


def short_repr(value):
    """repr(value) on one line (each run of white space one space), cut to 80 characters: an
    array's repr runs to many lines and thousands of characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 80 else text[:77] + "..."


class Refused(Exception):
    """A kind's converter cannot use the value: the message says it "is not" the kind's
    `expected`, or `expected` given here (a narrower one), or `instead` in place of both."""

    def __init__(self, expected=None, instead=None):
        super().__init__(expected)
        self.expected = expected
        self.instead = instead


class Kind:
    """A kind of argument: what it takes, said as "is not <expected>", and its converter."""

    def __init__(self, expected, convert):
        self.expected = expected
        self.convert = convert

    def __call__(self, value, where):
        try:
            return self.convert(value)
        except Refused as refused:
            if refused.instead:
                raise InvalidArgument(f"{where} {refused.instead}") from None
            raise InvalidArgument(f"{where} = {short_repr(value)} is not {refused.expected or self.expected}") from None


def _integer(lo, hi):
    def convert(value):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral) or not lo <= value <= hi:
            raise Refused
        return int(value)
    return convert


def _number(value):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise Refused
    return float(value)


def _boolean(value):
    if not isinstance(value, (bool, np.bool_)):
        raise Refused
    return bool(value)


def _string(value):
    if not isinstance(value, str):
        raise Refused
    return value


def _sequence_of(item):
    def convert(value):
        if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
            raise Refused
        return [item(v) for v in value]
    return convert


def _path(value):
    if isinstance(value, str) or hasattr(value, "__fspath__"):
        path = os.fspath(value)
        if isinstance(path, str):
            return path
    raise Refused


def optional(kind):
    """None, or a value of `kind`."""
    return Kind("None or " + kind.expected, lambda value: None if value is None else kind.convert(value))


def instance(cls, expected):
    """An object of class `cls`, passed as it is."""
    def convert(value):
        if not isinstance(value, cls):
            raise Refused
        return value
    return Kind(expected, convert)


BOOL = Kind("True or False", _boolean)
INT32 = Kind("an int that fits 32 bits", _integer(-2**31, 2**31 - 1))
UINT = Kind("a non-negative int", _integer(0, 2**64 - 1))
COUNT = Kind("a positive int", _integer(1, 2**64 - 1))
FLOAT = Kind("a number", _number)
STR = Kind("a string", _string)
STRS = Kind("a sequence of strings", _sequence_of(_string))
FLOATS = Kind("a sequence of numbers", _sequence_of(_number))
UINTS = Kind("a sequence of non-negative ints", _sequence_of(_integer(0, 2**64 - 1)))
PATH = Kind("a file's path (a str or an os.PathLike)", _path)
NAME = Kind("a model name or a mesh file's path (a str or an os.PathLike)", _path)
# Arrays, callbacks and the arguments the compiled module reads itself, naming what is wrong.
ANY = Kind("anything", lambda value: value)


def model(mesh_class):
    """A standard model's name or a mesh file's path (as a str), or an nbv.Mesh as it is."""
    def convert(value):
        return value if isinstance(value, mesh_class) else _path(value)
    return Kind("a model name, a mesh file or an nbv.Mesh", convert)


def _rays(value):
    if isinstance(value, str):
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)):
        if not -2**31 <= value < 2**31:
            raise Refused("an int that fits 32 bits")
        return int(value)
    raise Refused


def _callable(value):
    if not callable(value):
        raise Refused
    return value


def _viewspace(value):
    if value is None or isinstance(value, str) or hasattr(value, "__fspath__"):
        return value if value is None else _path(value)
    return value  # poses: the compiled module reads and checks the array


def _metric_names(value):
    # A string is a comma-separated list, as experiment() and the command line read one.
    return [name.strip() for name in value.split(",")] if isinstance(value, str) else _sequence_of(_string)(value)


RAYS = Kind("'released', 'released-shipped', 'full' or a pixel stride (an int)", _rays)
CALLABLE = Kind("a callable", _callable)
# A planner: a metric's name or weighted sum, "oracle", or a callable (a planner of one's own).
PLANNER = Kind("a metric's name, a weighted sum, 'oracle' or a callable",
               lambda value: value if callable(value) else _string(value))
VIEWSPACE = Kind("None, 'dome48', a view file's path or (N, 4, 4) poses", _viewspace)
METRIC_NAMES = Kind("a metric's name, 'all', a comma-separated list or a sequence of names", _metric_names)
CROP = Kind("a sequence of numbers or None", lambda value: None if value is None else _sequence_of(_number)(value))


def _default_text(value):
    """A default as a caller writes it: strings in double quotes, tuples of them too."""
    if isinstance(value, str):
        return '"' + value + '"'
    if isinstance(value, tuple):
        return "(" + ", ".join(_default_text(v) for v in value) + ("," if len(value) == 1 else "") + ")"
    return repr(value)


def signature_line(name, signature, width=100):
    """The line a docstring opens with, `name(a, b=1, **options) -> returns`, from a stub's
    signature (its parameters, defaults and return annotation), wrapped under the parenthesis."""
    parts = []
    for p in signature.parameters.values():
        if p.name == "self":
            continue
        if p.kind == p.VAR_KEYWORD:
            parts.append("**" + p.name)
        else:
            parts.append(p.name if p.default is p.empty else f"{p.name}={_default_text(p.default)}")
    returns = "" if signature.return_annotation is signature.empty else f" -> {signature.return_annotation}"
    lines, line = [], name + "("
    for i, part in enumerate(parts):
        text = part + (", " if i + 1 < len(parts) else ")" + returns)
        if len(line) + len(text.rstrip()) > width and line.strip() != name + "(":
            lines.append(line.rstrip())
            line = " " * (len(name) + 1)
        line += text
    if not parts:
        line += ")" + returns
    return "\n".join(lines + [line])


def checked(owner, compiled, options=None):
    """Decorates the signature of `compiled` (a function of the compiled module taking typed
    arguments), written as a Python function whose parameters are annotated with their kinds and
    whose body is never run: the function users call. It converts every argument by its kind,
    fills in the defaults, converts the keyword options of a signature ending in **options by
    the kinds of `options` (a dict name -> kind) into one dict, and calls `compiled` with them
    in order. A keyword it does not take raises InvalidArgument naming it with those it takes, as
    `owner` ("reconstruct", "Decider.decide"): Python's TypeError would not list them."""
    options = options or {}

    def decorate(stub):
        signature = inspect.signature(stub)
        is_method = "self" in signature.parameters
        parameters = [p for p in signature.parameters.values() if p.name != "self" and p.kind != p.VAR_KEYWORD]
        takes_options = any(p.kind == p.VAR_KEYWORD for p in signature.parameters.values())
        names = [p.name for p in parameters]
        position = {name: i for i, name in enumerate(names)}
        known = names + list(options)
        # Each parameter's kind (None: taken as it is), name in errors and default, made once:
        # the check runs between calls into the compiled module, with Python's caches cold.
        checks = [(None if p.annotation is ANY else p.annotation, f"{owner}: {p.name}", p.default) for p in parameters]
        option_checks = {name: (kind, f"{owner}: {name}") for name, kind in options.items()}
        missing = inspect.Parameter.empty

        def refuse(kwargs):
            unknown = [k for k in kwargs if k not in position and k not in option_checks]
            several = "s" if len(unknown) > 1 else ""
            quoted = ", ".join(f"'{k}'" for k in unknown)
            raise InvalidArgument(f"{owner}: unknown keyword{several} {quoted} (known: {', '.join(known)})")

        def convert(args, kwargs):
            """The arguments in `compiled`'s order, each converted; never sees the instance.
            (What inspect.Signature.bind() does, written out: it costs 100 us after a call.)"""
            if len(args) > len(names):
                raise TypeError(f"{owner}: {len(args)} positional arguments given, {len(names)} taken")
            values = list(args) + [missing] * (len(names) - len(args))
            given_options = {}
            for key, value in kwargs.items():
                i = position.get(key)
                if i is None:
                    if key not in option_checks:
                        refuse(kwargs)
                    given_options[key] = value
                elif i < len(args):
                    raise TypeError(f"{owner}: {key} is given twice")
                else:
                    values[i] = value
            arguments = []
            for value, (kind, where, default) in zip(values, checks):
                if value is missing:
                    if default is missing:
                        raise TypeError(f"{owner}: {where.split(': ')[-1]} is missing")
                    value = default
                arguments.append(value if kind is None else kind(value, where))
            if takes_options:
                arguments.append({k: option_checks[k][0](v, option_checks[k][1]) for k, v in given_options.items()})
            return arguments

        def call(*args, **kwargs):
            # A constructor's instance is not built until `compiled` runs: no frame of an error
            # raised before or by it may hold the instance, or a traceback's printer (pytest's
            # shows each frame's arguments) would call a method of the unbuilt instance.
            instance, args = (args[:1], args[1:]) if is_method else ((), args)
            try:
                return compiled(*instance, *convert(args, kwargs))
            finally:
                del instance

        call.__name__, call.__qualname__, call.__module__ = stub.__name__, owner, "nbv"
        shown = owner.split(".")[-1]  # a method's own name; a constructor's, the class's
        call.__doc__ = "\n" + signature_line(shown, signature) + "\n" + (compiled.__doc__ or "\n")
        call.__wrapped__ = compiled  # (inspect.signature() stops at __signature__)
        call.__signature__ = signature.replace(parameters=[p.replace(annotation=p.empty)
                                                          for p in signature.parameters.values()],
                                               return_annotation=signature.empty)
        return call

    return decorate


def method(cls, options=None):
    """Decorates the signature of a method of `cls` (a class of the compiled module), as
    checked() does, and puts the checked method in its place; "__init__" is the constructor,
    named as the class."""
    def decorate(stub):
        name = stub.__name__
        owner = cls.__name__ if name == "__init__" else f"{cls.__name__}.{name}"
        setattr(cls, name, checked(owner, getattr(cls, name), options)(stub))
        return getattr(cls, name)
    return decorate
