"""Names and addresses across formats: which names a `.s7g` chart can hold unquoted, and
IEC directly represented variables (``%IX0.1``) ↔ S7 addresses (``I0.1``).

An FB variable's name must read back as that variable wherever the chart uses it: not a
keyword, event or FB pin of GRAPH, not ``S`` or ``R`` (a permanent set/reset coil) or ``C``
(the interlock mark), not a step (``S3``) or block (``FB1``) reference. Other names get
a ``_`` suffix (the importer reports each rename).

IEC addresses: ``%I`` ``%Q`` ``%M`` with size ``X`` (or none) ``B`` ``W`` ``D`` and the
two-level ``byte.bit`` form map one to one (``%QX2.3`` → ``Q2.3``, ``%MW4`` → ``MW4``); a
one-level bit address ``%IXn`` counts bits from ``I0.0`` (``%IX9`` → ``I1.1``); ``L``
(64-bit) and deeper hierarchies have no S7 form.

Latin letters for a format that takes only ASCII names (``transliterate``): Cyrillic by
GOST 7.79-2000 system B (Table 4: ``Подача`` → ``Podacha``, ``Цех`` → ``Cex``), Russian
values where the languages differ (``и`` ``i``, ``щ`` ``shh``), without the system's marks
(`` ` `` and ``'``), which no identifier holds (``ъ`` and ``ь`` vanish, ``ы`` is ``y``, ``э``
``e``); other letters with a Latin base lose their marks (Unicode NFKD: ``Füll`` →
``Full``; ``ß`` ``ss``, ``ø`` ``o``, ``æ`` ``ae``); the rest stays as it is.
"""

from __future__ import annotations

import re
import unicodedata
from typing import Final

from s7graph.sequencer.params import pin

__all__ = ["iec_address", "is_graph_name", "s7_to_iec", "safe_name", "transliterate"]

_KEYWORDS: Final = frozenset(
    [
        "FUNCTION_BLOCK",
        "END_FUNCTION_BLOCK",
        "VAR",
        "END_VAR",
        "SYMBOLS",
        "END_SYMBOLS",
        "PERMANENT",
        "END_PERMANENT",
        "BEFORE",
        "AFTER",
        "CALL",
        "SEQUENCE",
        "END_SEQUENCE",
        "STEP",
        "INITIAL_STEP",
        "END_STEP",
        "INTERLOCK",
        "SUPERVISION",
        "TRANSITION",
        "FROM",
        "TO",
        "STOP",
        "S_ALL",
        "OR",
        "XOR",
        "AND",
        "NOT",
        "MOD",
        "SHL",
        "SHR",
        "SSR",
        "ROL",
        "ROR",
        "TRUE",
        "FALSE",
        "S1",
        "S0",
        "V1",
        "V0",
        "L1",
        "L0",
        "A1",
        "R1",
        "S",
        "R",
        "C",
    ]
)
_NAME: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_REFERENCE: Final = re.compile(r"(?i)(S\d+|(SFB|SFC|FB|FC|DB)\d+)")


def is_graph_name(name: str) -> bool:
    """``name`` can be an unquoted FB variable of a chart."""
    up = name.upper()
    if not _NAME.fullmatch(name) or up in _KEYWORDS or _REFERENCE.fullmatch(name):
        return False
    return pin(name) is None


def safe_name(name: str, taken: set[str]) -> str:
    """``name`` made a valid, unused (``taken`` holds upper-case names) FB variable name."""
    base = re.sub(r"[^A-Za-z0-9_]", "_", name) or "v"
    if not re.match(r"[A-Za-z_]", base):
        base = "v_" + base
    candidate = base if is_graph_name(base) else base + "_"
    n = 2
    while candidate.upper() in taken or not is_graph_name(candidate):
        candidate = f"{base}_{n}"
        n += 1
    return candidate


_IEC: Final = re.compile(r"%([IQM])([XBWDL]?)(\d+(?:\.\d+)*)", re.IGNORECASE)


def iec_address(text: str) -> str | None:
    """The S7 address of an IEC location, or None when it has none."""
    m = _IEC.fullmatch(text.strip())
    if m is None:
        return None
    area, size, nums = m.group(1).upper(), m.group(2).upper(), m.group(3).split(".")
    if size == "L":
        return None
    if size in ("", "X"):
        if len(nums) == 1:
            n = int(nums[0])
            return f"{area}{n // 8}.{n % 8}"
        if len(nums) == 2 and int(nums[1]) < 8:
            return f"{area}{int(nums[0])}.{int(nums[1])}"
        return None
    if len(nums) != 1:
        return None
    return f"{area}{size}{int(nums[0])}"


_S7: Final = re.compile(r"([IQM])([BWD]?)(\d+)(?:\.(\d))?", re.IGNORECASE)


def s7_to_iec(address: str) -> str | None:
    """The IEC location of an S7 address (I/Q/M areas), or None."""
    m = _S7.fullmatch(address.replace(" ", ""))
    if m is None:
        return None
    area, size, byte, bit = m.group(1).upper(), m.group(2).upper(), m.group(3), m.group(4)
    if bit is not None and not size:
        return f"%{area}X{int(byte)}.{bit}"
    if size and bit is None:
        return f"%{area}{size}{int(byte)}"
    return None


_GOST_B: Final = {
    "а": "a",
    "б": "b",
    "в": "v",
    "г": "g",
    "д": "d",
    "е": "e",
    "ё": "yo",
    "ж": "zh",
    "з": "z",
    "и": "i",
    "й": "j",
    "к": "k",
    "л": "l",
    "м": "m",
    "н": "n",
    "о": "o",
    "п": "p",
    "р": "r",
    "с": "s",
    "т": "t",
    "у": "u",
    "ф": "f",
    "х": "x",
    "ч": "ch",
    "ш": "sh",
    "щ": "shh",
    "ъ": "",
    "ы": "y",
    "ь": "",
    "э": "e",
    "ю": "yu",
    "я": "ya",
    "ґ": "g",
    "є": "ye",
    "і": "i",
    "ї": "yi",
    "ў": "u",
    "ѓ": "g",
    "ѕ": "z",
    "ј": "j",
    "ќ": "k",
    "љ": "l",
    "њ": "n",
    "џ": "dh",
}
"""GOST 7.79-2000 system B, lower case, without its marks (``ъ`` and ``ь`` are only one);
Russian, then Ukrainian, Belarusian and Macedonian letters; ``ц`` depends on the next
letter (``_cyrillic``)."""
_LATIN: Final = {"ß": "ss", "ø": "o", "æ": "ae", "œ": "oe", "đ": "d", "ł": "l", "þ": "th"}
"""Latin letters that Unicode does not decompose into a base letter and a mark."""


def _cyrillic(name: str, i: int) -> str | None:
    """GOST 7.79-2000 system B for ``name[i]`` (None: not a letter of its table): ``ц`` is
    ``c`` before ``i``, ``e``, ``y``, ``j``, else ``cz``; a capital spelled with several
    letters is all capitals beside another capital (``ЖУК`` → ``ZHUK``), else ``Zh``."""
    c = name[i]
    low = c.lower()
    if low == "ц":
        after = _GOST_B.get(name[i + 1 : i + 2].lower(), "")  # "" for ц, ъ, ь, no letter
        out = "c" if after[:1] in ("i", "e", "y", "j") else "cz"
    elif low in _GOST_B:
        out = _GOST_B[low]
    else:
        return None
    if c == low:
        return out
    after, before = name[i + 1 : i + 2], name[i - 1 : i] if i else ""
    return out.upper() if (after if after.isalpha() else before).isupper() else out.capitalize()


def transliterate(name: str) -> str:
    """``name`` in Latin letters, for a format that takes only ASCII names (the rule: the
    module's docstring); characters it has no Latin form for stay as they are."""
    out: list[str] = []
    for i, c in enumerate(name):
        if c.isascii():
            out.append(c)
            continue
        gost = _cyrillic(name, i)
        if gost is not None:
            out.append(gost)
            continue
        latin = _LATIN.get(c.lower())
        if latin is not None:
            out.append(latin if c.islower() else latin.capitalize())
            continue
        base = "".join(d for d in unicodedata.normalize("NFKD", c) if not unicodedata.combining(d))
        out.append(base if base.isascii() and base else c)
    return "".join(out)
