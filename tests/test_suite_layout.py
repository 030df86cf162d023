"""The test folders are not packages, so pytest imports each test module by its base name: two files
of one name in different folders stop the whole collection ("import file mismatch")."""

from collections import Counter
from pathlib import Path


def test_every_test_module_has_its_own_name():
    names = Counter(p.name for p in Path(__file__).parent.rglob("test_*.py"))
    assert not [n for n, c in names.items() if c > 1], names.most_common(3)
