"""The nbval sanitiser (tests/sanitize.cfg, read by nbval's own parser) masks memory addresses and
nothing else."""
import re
from pathlib import Path

import pytest
from nbval.plugin import get_sanitize_patterns

CFG = Path(__file__).resolve().parents[1] / "sanitize.cfg"


def _sanitize(text):
    """What nbval does with each stored and fresh output: every (regex, replace) of the file, in
    order."""
    for regex, replace in get_sanitize_patterns(CFG.read_text()):
        text = re.sub(regex, replace, text)
    return text


def test_the_file_holds_the_memory_address_pattern():
    assert [replace for _, replace in get_sanitize_patterns(CFG.read_text())] == ["0xADDRESS"]


@pytest.mark.parametrize("text, masked", [
    ("<Figure size 640x480 with 1 Axes at 0x7f3a2b1c4d50>", "<Figure size 640x480 with 1 Axes at 0xADDRESS>"),
    ("<function f at 0x55d5c8a3e2a0>", "<function f at 0xADDRESS>"),
    ("<object at 0x000001F2A3B4C5D0>", "<object at 0xADDRESS>"),  # Windows: 16 digits, upper case
    ("at 0x10a3b2c40, again at 0x7f0000000001.", "at 0xADDRESS, again at 0xADDRESS."),
])
def test_memory_addresses_are_masked(text, masked):
    assert _sanitize(text) == masked


@pytest.mark.parametrize("text", [
    "1000x20 pairs",                # a size: the 0x20 inside is not an address
    "figure of 630x360 pixels",
    "a 3x3 matrix, a 10x0 array",
    "flag 0xA, mask 0xff, 0x1F2A3",  # hex literals shorter than an address
    "ab0x7f3a2b1c4d50",             # not a word of its own
    "0x7f3a2b1c4d50aa11bb22",       # longer than 16 digits: not an address
    "no address here",
])
def test_other_text_is_left_alone(text):
    assert _sanitize(text) == text
