#!/usr/bin/python3
"""Counts test cases (not programs) from JUnit XML results and prints one summary line.

Usage: test_summary.py [--ctest-junit FILE --gtest-dir DIR] [--rostest-dir DIR] [--validation-junit FILE]
                       [--install-junit FILE]

--ctest-junit: ctest --output-junit FILE (one entry per registered test program, with its exit status);
--gtest-dir:   the folder GTEST_OUTPUT=xml:DIR/ filled (one file per gtest program, one entry per case);
--rostest-dir: catkin's test_results folder (rosunit-*.xml: the cases of each rostest's gtest node;
               rostest-*.xml: one wrapper entry per .test file, failed when the launch or the node failed;
               gtest-*.xml: the catkin gtests that need no master);
--validation-junit: scripts/validate --junit FILE (one case per benchmark, resolution and quantity; a missing file
               counts as one failed case).

A gtest program whose cases all passed but which failed in ctest (crash, exit code) counts as one more failed
case; a program ctest ran without gtest XML (a script) counts as one case. A rostest wrapper that failed adds one
failed case unless its node already reported a failed case. Skipped cases (GTEST_SKIP, e.g. missing ../shared
data) are counted and listed as skipped, never as passed; with --expect-shared-data a case skipped for missing
shared data (its message holds "needs ../shared/data", test/shared_data.h) counts as failed. Prints
    tests: N passed, N failed, N skipped
last and exits 1 when anything failed or nothing ran.
"""
import argparse
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET

SHARED_DATA_MARK = "needs ../shared/data"  # the skip message of RC_SKIP_WITHOUT_SHARED_DATA (test/shared_data.h)


class Tally:
    def __init__(self, name):
        self.name = name
        self.passed, self.failed, self.skipped = [], [], []

    def add(self, case, state, why=""):
        {"passed": self.passed, "failed": self.failed, "skipped": self.skipped}[state].append((case, why))

    def total(self):
        return len(self.passed) + len(self.failed) + len(self.skipped)


def message_text(text):
    """A gtest failure or skip message without its leading "file:line" line, on one line."""
    lines = [l.strip() for l in (text or "").strip().splitlines() if l.strip()]
    if lines and re.match(r"^\S+:\d+$", lines[0]):
        lines = lines[1:]
    return " ".join(lines)


def gtest_cases(path):
    """(suite.case, state, message) for every case of one gtest XML file."""
    cases = []
    root = ET.parse(path).getroot()
    for tc in root.iter("testcase"):
        name = "%s.%s" % (tc.get("classname", "?"), tc.get("name", "?"))
        failure = tc.find("failure")
        if failure is None:
            failure = tc.find("error")
        skipped = tc.find("skipped")
        if failure is not None:
            cases.append((name, "failed", message_text(failure.get("message") or failure.text)))
        elif skipped is not None or tc.get("result") == "skipped" or tc.get("status") == "notrun":
            cases.append((name, "skipped", message_text(skipped.get("message") if skipped is not None else "")))
        else:
            cases.append((name, "passed", ""))
    return cases


def core_tally(ctest_junit, gtest_dir):
    tally = Tally("gtest (core, plain CMake, no ROS)")
    programs = []  # (name, ctest passed)
    if ctest_junit and os.path.exists(ctest_junit):
        for tc in ET.parse(ctest_junit).getroot().iter("testcase"):
            ok = tc.get("status") == "run" and tc.find("failure") is None and tc.find("error") is None
            programs.append((tc.get("name"), ok))
    for name, ok in programs:
        xml = os.path.join(gtest_dir, name + ".xml")
        cases = gtest_cases(xml) if os.path.exists(xml) else None
        if cases is None:
            tally.add(name, "passed" if ok else "failed", "" if ok else "program failed (no gtest XML)")
            continue
        for case, state, why in cases:
            tally.add("%s: %s" % (name, case), state, why)
        if not ok and not any(state == "failed" for _, state, _ in cases):
            tally.add(name, "failed", "program failed after its cases (crash or exit code)")
    return tally, len(programs)


def ros_tally(result_dir):
    tally = Tally("rostest (catkin package)")
    # catkin writes MISSING-rostest-<name>.xml (one failed case) for a rostest that produced no results, e.g.
    # a launch file that does not parse: it counts as failed, never as absent.
    wrappers = sorted(glob.glob(os.path.join(result_dir, "**", "rostest-*.xml"), recursive=True) +
                      glob.glob(os.path.join(result_dir, "**", "MISSING-rostest-*.xml"), recursive=True))
    for wrapper in wrappers:
        base = os.path.basename(wrapper)
        base = base[base.index("rostest-") + len("rostest-"):-len(".xml")]  # test_ros_<name>
        name = base[len("test_ros_"):] if base.startswith("test_ros_") else base
        unit = os.path.join(os.path.dirname(wrapper), "rosunit-%s.xml" % name)
        cases = gtest_cases(unit) if os.path.exists(unit) else []
        for case, state, why in cases:
            tally.add("%s: %s" % (name, case), state, why)
        wrapper_cases = gtest_cases(wrapper)
        wrapper_failed = any(state == "failed" for _, state, _ in wrapper_cases)
        if (wrapper_failed or not cases) and not any(state == "failed" for _, state, _ in cases):
            msg = next((why for _, state, why in wrapper_cases if state == "failed"), "")
            tally.add(name + ".test", "failed", msg or "no test cases ran")
    # catkin_add_gtest programs (no master, test/ros/nomaster): gtest-<name>.xml, or MISSING-gtest-<name>.xml
    # (one failed case) when the program produced no results.
    programs = sorted(glob.glob(os.path.join(result_dir, "**", "gtest-*.xml"), recursive=True) +
                      glob.glob(os.path.join(result_dir, "**", "MISSING-gtest-*.xml"), recursive=True))
    for program in programs:
        base = os.path.basename(program)
        name = base[base.index("gtest-") + len("gtest-"):-len(".xml")]
        cases = gtest_cases(program)
        for case, state, why in cases:
            tally.add("%s: %s" % (name, case), state, why)
        if not cases:
            tally.add(name, "failed", "no test cases ran")
    return tally, (len(wrappers), len(programs))


def junit_tally(path, name, program):
    """The cases of a JUnit file a script wrote (a missing file is one failed case)."""
    tally = Tally(name)
    if not os.path.exists(path):
        tally.add(program, "failed", "no results (%s)" % path)
        return tally, 0
    cases = gtest_cases(path)
    for case, state, why in cases:
        tally.add(case, state, why)
    return tally, len(cases)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ctest-junit")
    parser.add_argument("--gtest-dir")
    parser.add_argument("--rostest-dir")
    parser.add_argument("--validation-junit")
    parser.add_argument("--install-junit")
    parser.add_argument("--expect-shared-data", action="store_true",
                        help="a case skipped for missing ../shared/data counts as failed (CI has the data)")
    args = parser.parse_args()
    tallies = []
    if args.ctest_junit:
        tally, programs = core_tally(args.ctest_junit, args.gtest_dir or "")
        tallies.append((tally, "%d programs" % programs))
    if args.rostest_dir:
        tally, (launches, programs) = ros_tally(args.rostest_dir)
        tallies.append((tally, "%d launch files and %d gtest programs without a master" % (launches, programs)))
    if args.validation_junit:
        tally, quantities = junit_tally(args.validation_junit, "validation (scripts/validate --quick)",
                                        "scripts/validate")
        tallies.append((tally, "%d quantities" % quantities))
    if args.install_junit:
        tally, checks = junit_tally(args.install_junit, "install space (scripts/check_install)",
                                    "scripts/check_install")
        tallies.append((tally, "%d checks" % checks))
    for tally, unit in tallies:
        if args.expect_shared_data:
            missing = [(case, why) for case, why in tally.skipped if SHARED_DATA_MARK in why]
            tally.skipped = [(case, why) for case, why in tally.skipped if SHARED_DATA_MARK not in why]
            tally.failed += [(case, "skipped, but ../shared/data was expected: " + why) for case, why in missing]
        for case, why in tally.skipped:
            print("  skipped: %s%s" % (case, (" (" + why + ")") if why else ""))
        for case, why in tally.failed:
            print("  FAILED: %s%s" % (case, (" (" + why + ")") if why else ""))
        print("%s: %d cases in %s: %d passed, %d failed, %d skipped" %
              (tally.name, tally.total(), unit, len(tally.passed), len(tally.failed), len(tally.skipped)))
    passed = sum(len(t.passed) for t, _ in tallies)
    failed = sum(len(t.failed) for t, _ in tallies)
    skipped = sum(len(t.skipped) for t, _ in tallies)
    print("tests: %d passed, %d failed, %d skipped" % (passed, failed, skipped))
    return 1 if failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
