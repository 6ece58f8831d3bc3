#!/usr/bin/env python3
"""Counts gtest/rostest JUnit XML results under a folder; prints failures, the skipped count (when any)
on a line of its own, and a final 'N passed, N failed' line; exits 1 on any failure or when nothing ran.
A test skipped with no reason given counts as failed: gtest writes every test of a suite whose
SetUpTestSuite failed as skipped, with no message and no failure anywhere (this project's GTEST_SKIPs all
say why). A rostest's own wrapper case (classname rostest.runner.RosTest, in rostest-*.xml) counts only
when it failed (its test node crashed, timed out or wrote no result): passed, it says the node ran, whose
cases are counted from their own result, and counting it too added one pass per rostest. An optional
second argument is make run_tests' exit status: non-zero (make stopped, or timed out, before every test
ran) counts one failure more."""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def main(root: Path, make_status: int = 0) -> int:
    passed, failed, skipped, failures = 0, 0, 0, []
    if make_status != 0:
        failed += 1
        failures.append(f"make run_tests exited {make_status}: the tests it had not reached left no result")
    files = sorted(root.rglob("*.xml")) if root.is_dir() else []
    for f in files:
        try:
            tree = ET.parse(f)
        except ET.ParseError as e:
            failed += 1
            failures.append(f"{f.name}: unreadable result ({e})")
            continue
        for case in tree.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            bad = case.find("failure") is not None or case.find("error") is not None
            if bad:
                failed += 1
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
    sys.exit(main(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 0))
