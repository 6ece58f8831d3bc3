#!/usr/bin/env python3
"""Counts gtest/rostest JUnit XML results under a folder; prints failures, the skipped count (when any)
on a line of its own, and a final 'N passed, N failed' line; exits 1 on any failure or when nothing ran.
A test skipped with no reason given counts as failed: gtest writes every test of a suite whose
SetUpTestSuite failed as skipped, with no message and no failure anywhere (this project's GTEST_SKIPs all
say why). A rostest's own wrapper case (classname rostest.runner.RosTest, in rostest-*.xml) counts only
when it failed (its test node crashed, timed out or wrote no result): passed, it says the node ran, whose
cases are counted from their own result, and counting it too added one pass per rostest.
An optional second argument is ctest's exit status, and a third the file ctest lists its failed tests in
(Testing/Temporary/LastTestsFailed.log, lines 'N:name'). A gtest binary ctest saw fail whose result file
(or catkin's MISSING-gtest-<name>.xml, written for a binary that wrote none) shows no failure exited
non-zero after writing it (a crash on exit, in a destructor or at shutdown): one
failure more, by name; catkin's run_tests ignored exit statuses, so such a crash passed. Any other test ctest
saw fail counts one more only when no result file shows a failure at all (its kind's result names no
failure either way, and the run must not pass). A non-zero status with no test listed failed (ctest
stopped, or timed out, before every test ran) counts one failure more."""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def ctest_failures(listing: Path) -> list:
    """The names in ctest's LastTestsFailed.log ('N:name' lines); none when it is missing."""
    try:
        lines = listing.read_text().splitlines()
    except OSError:
        return []
    return [line.split(":", 1)[1].strip() for line in lines if ":" in line]


def main(root: Path, status: int = 0, failed_listing: Path = None) -> int:
    passed, failed, skipped, failures = 0, 0, 0, []
    exited = ctest_failures(failed_listing) if failed_listing else []
    if status != 0 and not exited:
        failed += 1
        failures.append(f"ctest exited {status} with no test failed: the tests it had not reached left no result")
    bad_in = {}  # result file name -> failures counted in it
    files = sorted(root.rglob("*.xml")) if root.is_dir() else []
    for f in files:
        try:
            tree = ET.parse(f)
        except ET.ParseError as e:
            failed += 1
            bad_in[f.name] = bad_in.get(f.name, 0) + 1
            failures.append(f"{f.name}: unreadable result ({e})")
            continue
        for case in tree.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            bad = case.find("failure") is not None or case.find("error") is not None
            if bad:
                failed += 1
                bad_in[f.name] = bad_in.get(f.name, 0) + 1
                node = case.find("failure") if case.find("failure") is not None else case.find("error")
                msg = (node.get("message") or node.text or "").strip().splitlines()
                failures.append(f"{name}: {msg[0] if msg else 'failed'}")
            elif case.find("skipped") is not None:
                node = case.find("skipped")
                why = (node.get("message") or node.text or "").strip().splitlines()[1:]  # after "file:line"
                if any(line.strip() for line in why):
                    skipped += 1
                else:
                    failed += 1
                    failures.append(f"{name}: skipped with no reason given (a failing SetUpTestSuite?)")
            elif case.get("status") == "notrun":
                skipped += 1
            elif case.get("classname") != "rostest.runner.RosTest":
                passed += 1
    any_bad = failed > 0
    for test in exited:  # catkin names them _ctest_<package>_<kind>_<name>; a gtest's result is gtest-<name>.xml
        kind, sep, rest = test.partition("_gtest_")
        if sep and kind.startswith("_ctest_"):
            # catkin writes MISSING-gtest-<name>.xml, one failure, for a binary that wrote no result
            if bad_in.get(f"gtest-{rest}.xml", 0) + bad_in.get(f"MISSING-gtest-{rest}.xml", 0) == 0:
                failed += 1
                failures.append(f"{test}: exited non-zero, and its result gtest-{rest}.xml shows no failure "
                                f"(a crash after writing it, on exit?)")
        elif not any_bad:
            failed += 1
            failures.append(f"{test}: exited non-zero, and no result shows a failure")
    for line in failures:
        print(f"FAILED {line}")
    if passed + failed == 0:
        print("no test results found under", root)
        failed = 1
    if skipped:
        print(f"{skipped} skipped")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 0,
                  Path(sys.argv[3]) if len(sys.argv) > 3 else None))
