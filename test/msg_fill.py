"""Deterministic, fully populated instances of any rosidl message type.

Used by a publisher in one process and the checking subscriber in another: both
build the same message from the type alone, so equality proves every field made
the trip.
"""
from __future__ import annotations

import importlib


def _scalar(type_name: str, salt: int):
    if type_name in ("float", "double", "float32", "float64"):
        return 0.25 * (salt + 1) if type_name in ("float", "float32") else 1.0e-6 * (salt + 1) / 3
    if type_name == "boolean":
        return salt % 2 == 1
    if type_name in ("string", "wstring"):
        return f"value_{salt}"
    if type_name in ("octet", "uint8", "byte", "char"):
        return (salt * 7) % 256 if type_name != "char" else "a"
    if type_name.startswith("uint"):
        return (salt * 3 + 1) % (100 if type_name in ("uint8", "uint16") else 10**6)
    if type_name.startswith("int"):
        return -((salt * 3 + 1) % (100 if type_name in ("int8", "int16") else 10**6))
    return None


def _value(type_name: str, salt: int):
    if type_name.endswith("]") and "[" in type_name:  # fixed-size array, e.g. boolean[3]
        inner, size = type_name[:-1].split("[")
        return [_value(inner, salt + i) for i in range(int(size))]
    if type_name.startswith("sequence<"):
        inner = type_name[len("sequence<"):-1].split(",")[0]
        return [_value(inner, salt + i) for i in range(3)]
    scalar = _scalar(type_name, salt)
    if scalar is not None:
        return scalar
    package, name = type_name.split("/")
    return filled(getattr(importlib.import_module(f"{package}.msg"), name)(), salt)


def filled(message, salt: int = 0):
    """Return ``message`` with every field set to a value derived from ``salt``."""
    for index, (field, type_name) in enumerate(message.get_fields_and_field_types().items()):
        value = _value(type_name, salt + 11 * index)
        if isinstance(value, (list,)) and type_name.startswith("sequence<"):
            inner = type_name[len("sequence<"):-1]
            if inner in ("double", "float"):
                value = [float(v) for v in value]
        setattr(message, field, value)
    return message
