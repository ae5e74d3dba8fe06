"""JSON Schema layer (workflow/schemas/config.schema.yaml): number coercion, defaults, the first violation."""
from __future__ import annotations

import copy
import math
import re
from functools import lru_cache

import yaml
from jsonschema import Draft202012Validator, validators

from ureterfsi import REPO_ROOT

from .errors import ConfigError, dotted, fmt

SCHEMA_PATH = REPO_ROOT / "workflow" / "schemas" / "config.schema.yaml"


@lru_cache(maxsize=1)
def load_schema() -> dict:
    return yaml.safe_load(SCHEMA_PATH.read_text())


def _prescan(node, path=()) -> None:
    """Refuse what JSON Schema cannot see in YAML data: non-string keys and non-finite numbers."""
    if isinstance(node, dict):
        for k, v in node.items():
            if not isinstance(k, str):
                raise ConfigError(dotted(path + (str(k),)),
                                  f"keys must be strings, got {type(k).__name__} {k!r} (quote it: \"{k}\")")
            _prescan(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _prescan(v, path + (i,))
    elif isinstance(node, float) and not math.isfinite(node):
        raise ConfigError(dotted(path), f"must be a finite number, got {node}")


def _fill_defaults(node, schema: dict) -> None:
    """Insert schema defaults of missing optional keys (in place), recursing into present objects."""
    if not isinstance(node, dict):
        return
    for key, sub in schema.get("properties", {}).items():
        if key not in node and "default" in sub:
            node[key] = copy.deepcopy(sub["default"])
        if key in node:
            _fill_defaults(node[key], sub)
    for pattern, sub in schema.get("patternProperties", {}).items():
        for key, value in node.items():
            if isinstance(key, str) and re.search(pattern, key):
                _fill_defaults(value, sub)


# YAML 1.2 (and JSON) read 5.0e4 as a number; PyYAML, and with it Snakemake's config loader, implement
# YAML 1.1, whose float syntax needs a dot and a signed exponent, so 5.0e4 arrives as the string '5.0e4'.
_YAML12_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_DECIMAL_COMMA = re.compile(r"[-+]?[0-9]*,[0-9]+")


def _resolve(schema: dict, root: dict) -> dict:
    ref = schema.get("$ref", "")
    if ref.startswith("#/$defs/"):
        return {**root["$defs"][ref.split("/")[-1]], **{k: v for k, v in schema.items() if k != "$ref"}}
    return schema


def _coerce_numbers(node, schema: dict, root: dict):
    """Convert (in place) strings in YAML 1.2 number syntax where the schema expects a number."""
    schema = _resolve(schema, root)
    if isinstance(node, dict):
        subs = schema.get("properties", {})
        pats = schema.get("patternProperties", {})
        for k, v in node.items():
            sub = subs.get(k) or next((ps for p, ps in pats.items() if isinstance(k, str) and re.search(p, k)), None)
            if sub is not None:
                node[k] = _coerce_numbers(v, sub, root)
    elif isinstance(node, list) and isinstance(schema.get("items"), dict):
        node[:] = [_coerce_numbers(v, schema["items"], root) for v in node]
    elif isinstance(node, str) and schema.get("type") == "number" and _YAML12_FLOAT.fullmatch(node.strip()):
        return float(node)
    return node


def _schema_message(err) -> tuple[str, str]:
    """(dotted key, one-line constraint) of a jsonschema ValidationError."""
    path = list(err.absolute_path)
    v, val, inst = err.validator, err.validator_value, err.instance
    if v == "required":
        missing = [k for k in val if isinstance(inst, dict) and k not in inst]
        return dotted(path + [missing[0]]), "required key is missing"
    if v == "additionalProperties":
        props = err.schema.get("properties", {})
        patterns = list(err.schema.get("patternProperties", {}))
        extra = sorted(k for k in inst if k not in props and not any(re.search(p, k) for p in patterns))
        allowed = (f"allowed keys: {', '.join(props)}" if props else
                   f"keys must match {' or '.join(patterns)}")
        return dotted(path + [extra[0]]), f"unknown key (misspelt?); {allowed}"
    if v == "type":
        if val == "integer" and isinstance(inst, float):
            fix = f": write {int(inst)}" if inst.is_integer() else ""
            return dotted(path), f"must be an integer, got the float {inst!r}{fix}"
        hint = ""
        if val == "number" and isinstance(inst, str) and _DECIMAL_COMMA.fullmatch(inst.strip()):
            hint = f" (decimal comma? write {inst.strip().replace(',', '.')})"
        return dotted(path), f"must be of type {val}, got {type(inst).__name__} {fmt(inst)}{hint}"
    ops = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}
    if v in ops:
        return dotted(path), f"must be {ops[v]} {fmt(val)}, got {fmt(inst)}"
    if v == "enum":
        return dotted(path), f"must be one of {', '.join(map(str, val))}; got {fmt(inst)}"
    if v == "multipleOf":
        return dotted(path), f"must be a multiple of {fmt(val)}, got {fmt(inst)}"
    if v in ("minItems", "minProperties"):
        return dotted(path), f"must have at least {val} entr{'y' if val == 1 else 'ies'}, got {len(inst)}"
    if v == "minLength":
        return dotted(path), f"must be a non-empty string, got {fmt(inst)}"
    return dotted(path), err.message


@lru_cache(maxsize=None)
def _section_schema(sections: tuple | None) -> dict:
    """The schema, or with `sections` the schema of a mapping of exactly those top-level sections (the same
    definitions: the configuration file of one solve holds only the sections it reads, runs.run_config)."""
    root = load_schema()
    if sections is None:
        return root
    return {**root, "properties": {k: root["properties"][k] for k in sections}, "required": list(sections)}


@lru_cache(maxsize=None)
def _validator(sections: tuple | None = None):
    """Draft 2020-12 validator of the schema (of `sections`, _section_schema) whose ``integer`` excludes floats
    (JSON Schema accepts 15.0)."""
    checker = Draft202012Validator.TYPE_CHECKER.redefine(
        "integer", lambda _, inst: isinstance(inst, int) and not isinstance(inst, bool))
    return validators.extend(Draft202012Validator, type_checker=checker)(_section_schema(sections))


def _validate_schema(cfg: dict, sections: tuple | None = None) -> None:
    errors = [_schema_message(e) for e in _validator(sections).iter_errors(cfg)]
    if errors:
        key, text = min(errors, key=lambda kt: (kt[0].split("."), kt[1]))
        raise ConfigError(key, text)


def validate_schema(cfg: dict, sections: tuple | None = None) -> None:
    """Normalise `cfg` in place (YAML 1.2 number strings where the schema expects a number become floats, see
    _YAML12_FLOAT; missing optional keys get their schema defaults) and raise ConfigError on the first schema
    violation by dotted key. With `sections`: `cfg` holds exactly those top-level sections."""
    schema = _section_schema(sections)
    _coerce_numbers(cfg, schema, schema)
    _prescan(cfg)
    _fill_defaults(cfg, schema)
    _validate_schema(cfg, sections)


def schema_defaults(section: str) -> dict:
    """The schema's defaults of a top-level section, as validate_config fills them in."""
    out: dict = {}
    _fill_defaults(out, load_schema()["properties"][section])
    return out
