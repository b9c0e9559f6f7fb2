"""The memo of values per inputs: a hit needs the very owner objects, never equal ones, and the
table empties itself at its limit."""

from amble.simulation.memo import Memo


class Owner:
    def __eq__(self, other):  # equal to everything: the memo must not care
        return True

    __hash__ = object.__hash__


def test_hits_need_the_same_objects():
    a, b, m = Owner(), Owner(), Memo(4)
    m.put((id(a), 1), "value", a)
    assert m.get((id(a), 1), a) == "value"
    assert m.get((id(a), 1), b) is None  # equal but another object: an id reused after a is gone
    assert m.get((id(a), 1)) is None and m.get((id(a), 1), a, a) is None  # other owner counts
    assert m.get((id(a), 2), a) is None


def test_several_owners_and_the_limit():
    owners, m = [Owner() for _ in range(3)], Memo(2)
    m.put(("k", 0), 0, owners[0], owners[1])
    assert m.get(("k", 0), owners[0], owners[1]) == 0
    assert m.get(("k", 0), owners[1], owners[0]) is None
    m.put(("k", 1), 1, owners[2])
    m.put(("k", 2), 2, owners[2])  # a third entry: the table starts again
    assert m.get(("k", 0), owners[0], owners[1]) is None and m.get(("k", 2), owners[2]) == 2
    m.clear()
    assert m.get(("k", 2), owners[2]) is None
