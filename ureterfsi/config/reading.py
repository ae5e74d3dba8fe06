"""YAML files and --config values read as Snakemake reads them, refusing what PyYAML lets through silently."""
from __future__ import annotations

import copy
import re
from pathlib import Path

import yaml

from .errors import ConfigError, dotted


def deep_merge(base: dict, overrides: dict) -> dict:
    """Return `base` updated recursively by `overrides` (nested dicts merged, other values replaced)."""
    out = copy.deepcopy(base)
    for k, v in (overrides or {}).items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


_INT_TAG, _NULL_TAG, _MERGE_TAG = "tag:yaml.org,2002:int", "tag:yaml.org,2002:null", "tag:yaml.org,2002:merge"
_LEADING_ZERO = re.compile(r"[-+]?0[0-9_]+")   # YAML 1.1: 010 is octal 8, 09 a string


def _plain_number(node) -> bool:
    return (isinstance(node, yaml.ScalarNode) and node.style is None
            and node.tag in (_INT_TAG, "tag:yaml.org,2002:float"))


def _where(name: str, node) -> str:
    return f"{name}:{node.start_mark.line + 1}"


def _between(text: str, a, b) -> str:
    return text[a.end_mark.index:b.start_mark.index]


def _comma_between(text: str, a, b) -> bool:
    return _between(text, a, b).strip() == ","


def _list_decimal_comma(text: str, items: list, i: int) -> bool:
    """Items i-1, i of a flow sequence are one number with a decimal comma: ``[0,005]`` (YAML 1.1: [0, 5], the
    second with a leading zero) or ``[0,5, 1.0]`` (two integers joined by a bare ',' in a list whose other
    separators have a blank; ``[1,2,3]`` is not flagged)."""
    a, b = items[i - 1], items[i]
    if not (_plain_number(a) and _plain_number(b) and b.tag == _INT_TAG and _comma_between(text, a, b)):
        return False
    if _LEADING_ZERO.fullmatch(b.value):
        return True
    return (a.tag == _INT_TAG and _between(text, a, b) == ","
            and any(_between(text, x, y) != "," for x, y in zip(items, items[1:])))


def _check_nodes(node, path: tuple, name: str, text: str) -> None:
    """Refuse what PyYAML reads silently: duplicate keys, decimal commas in flow style, leading-zero ints."""
    if isinstance(node, yaml.MappingNode):
        seen, prev = {}, None
        for knode, vnode in node.value:
            if knode.tag == _MERGE_TAG:
                _check_nodes(vnode, path, name, text)
                continue
            if not isinstance(knode, yaml.ScalarNode):
                _check_nodes(vnode, path + ("?",), name, text)
                continue
            if (node.flow_style and prev is not None and _plain_number(prev[1]) and knode.style is None
                    and re.fullmatch(r"[0-9]+", knode.value) and vnode.tag == _NULL_TAG and vnode.value == ""
                    and _comma_between(text, prev[1], knode)):
                raise ConfigError(dotted(path + (prev[0],)),
                                  f"decimal comma in {prev[1].value},{knode.value} ({_where(name, knode)}): write "
                                  f"{prev[1].value}.{knode.value} (in a {{...}} mapping a comma separates entries)")
            ident = (knode.tag, knode.value)
            if ident in seen:
                raise ConfigError(dotted(path + (knode.value,)),
                                  f"key given twice ({seen[ident]} and {_where(name, knode)}); YAML keeps the "
                                  f"second silently: remove one")
            seen[ident] = _where(name, knode)
            _check_nodes(vnode, path + (knode.value,), name, text)
            prev = (knode.value, vnode)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            if node.flow_style and i and _list_decimal_comma(text, node.value, i):
                a = node.value[i - 1].value
                raise ConfigError(dotted(path + (i - 1,)),
                                  f"decimal comma in {a},{item.value} ({_where(name, item)}): write {a}.{item.value} "
                                  f"(in a [...] list a comma separates entries)")
            _check_nodes(item, path + (i,), name, text)
    elif (isinstance(node, yaml.ScalarNode) and node.style is None and node.tag == _INT_TAG
          and _LEADING_ZERO.fullmatch(node.value)):
        raise ConfigError(dotted(path), f"{node.value} has a leading zero, which YAML 1.1 reads as an octal "
                                         f"number ({_where(name, node)}): write {node.value.lstrip('0') or '0'}")


def _load_yaml(text: str, name: str, path: tuple = ()):
    """The YAML document `text` (None if empty) by PyYAML's safe loader, refusing syntax errors (as
    name:line:column), duplicate keys, decimal commas in flow style and leading-zero integers."""
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, path, name, text)
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{name}:{mark.line + 1}:{mark.column + 1}" if mark else name
        detail = "; ".join(str(x) for x in (exc.context, exc.problem) if x)
        raise ConfigError(where, f"YAML syntax error: {detail}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(name, f"YAML error: {exc}") from None
    finally:
        loader.dispose()


def read_yaml(path) -> dict:
    """The mapping of a YAML file as Snakemake reads it (PyYAML safe loader), with the refusals of _load_yaml."""
    name = str(path)
    try:
        text = Path(path).read_text()
    except FileNotFoundError:
        raise ConfigError(name, "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(name, f"cannot read the file: {exc}") from None
    data = _load_yaml(text, name)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(name, f"must be a YAML mapping of sections, got {type(data).__name__}")
    return data


def read_config_args(entries) -> dict:
    """The overrides of ``snakemake --config KEY=VALUE ...``, each VALUE read like a config file (_load_yaml).
    Snakemake reads a nested VALUE with PyYAML's BaseLoader, every scalar a string: ``solver='{newton_max_iterations:
    20}'`` arrived as '20' and was refused as not an integer, ``mesh='{optimize: false}'`` as not a boolean."""
    out: dict = {}
    for entry in entries or ():
        key, _, text = entry.partition("=")
        out = deep_merge(out, {key: _load_yaml(text.strip("'\""), f"--config {key}", (key,))})
    return out
