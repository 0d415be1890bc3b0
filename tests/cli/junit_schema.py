"""A checker for the JUnit XML structure CI systems read (the Ant / Maven Surefire format that
Jenkins' junit-10.xsd describes, which GitLab and GitHub test reporters accept): no schema file
ships with the tests, so its rules are written out here. check(path) raises AssertionError with
what is wrong."""
import re
import xml.etree.ElementTree as ET

DECIMAL = re.compile(r"^-?\d+(\.\d+)?([eE][-+]?\d+)?$")
COUNT = re.compile(r"^\d+$")

SUITES_ATTRS = {"name", "tests", "failures", "errors", "skipped", "disabled", "time"}
SUITE_ATTRS = {"name", "tests", "failures", "errors", "skipped", "disabled", "time", "timestamp",
               "hostname", "id", "package", "file", "log", "url", "version", "group"}
CASE_ATTRS = {"name", "classname", "time", "assertions", "status", "file", "line", "group"}
OUTCOMES = {"skipped", "error", "failure"}


def _attrs(e, allowed, required):
    extra = set(e.attrib) - allowed
    assert not extra, f"<{e.tag}> has attributes the schema does not allow: {sorted(extra)}"
    for a in required:
        assert a in e.attrib, f"<{e.tag}> lacks the required attribute '{a}'"
    for a in ("tests", "failures", "errors", "skipped", "disabled"):
        if a in e.attrib:
            assert COUNT.match(e.attrib[a]), f"<{e.tag} {a}=\"{e.attrib[a]}\"> is not a count"
    if "time" in e.attrib:
        assert DECIMAL.match(e.attrib["time"]), f"<{e.tag} time=\"{e.attrib['time']}\">"


def _case(c):
    _attrs(c, CASE_ATTRS, ["name", "classname"])
    tags = [x.tag for x in c]
    outcomes = [t for t in tags if t in OUTCOMES]
    assert len(outcomes) <= 1, f"testcase '{c.get('name')}' has several outcomes {outcomes}"
    order = {"skipped": 0, "error": 0, "failure": 0, "system-out": 1, "system-err": 2}
    for t in tags:
        assert t in order, f"testcase '{c.get('name')}' has an element <{t}>"
    ranks = [order[t] for t in tags]
    assert ranks == sorted(ranks), f"testcase '{c.get('name')}': elements out of order {tags}"
    for x in c:
        if x.tag in ("error", "failure"):
            assert set(x.attrib) <= {"message", "type"}, x.attrib
        if x.tag == "skipped":
            assert set(x.attrib) <= {"message"}, x.attrib
        if x.tag in ("system-out", "system-err"):
            assert len(x) == 0, f"<{x.tag}> holds elements"
    return outcomes[0] if outcomes else "passed"


def _suite(s):
    _attrs(s, SUITE_ATTRS, ["name", "tests"])
    order = {"properties": 0, "testcase": 1, "system-out": 2, "system-err": 3}
    ranks = []
    counts = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    for x in s:
        assert x.tag in order, f"testsuite '{s.get('name')}' has an element <{x.tag}>"
        ranks.append(order[x.tag])
        if x.tag == "properties":
            for p in x:
                assert p.tag == "property" and set(p.attrib) == {"name", "value"}, p.attrib
        if x.tag == "testcase":
            outcome = _case(x)
            counts["tests"] += 1
            counts["failures"] += outcome == "failure"
            counts["errors"] += outcome == "error"
            counts["skipped"] += outcome == "skipped"
    assert ranks == sorted(ranks), f"testsuite '{s.get('name')}': elements out of order"
    for k, n in counts.items():
        if k in s.attrib:
            assert int(s.get(k)) == n, f"testsuite '{s.get('name')}' says {k}={s.get(k)}, has {n}"
    return counts


def check(path):
    """Validates the file; returns the root element."""
    root = ET.parse(path).getroot()
    if root.tag == "testsuite":
        _suite(root)
        return root
    assert root.tag == "testsuites", f"the root is <{root.tag}>"
    _attrs(root, SUITES_ATTRS, [])
    total = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    for s in root:
        assert s.tag == "testsuite", f"<testsuites> holds <{s.tag}>"
        for k, n in _suite(s).items():
            total[k] += n
    for k, n in total.items():
        if k in root.attrib:
            assert int(root.get(k)) == n, f"testsuites says {k}={root.get(k)}, has {n}"
    return root
