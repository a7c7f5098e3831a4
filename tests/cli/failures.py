"""The end of a command-line test script: each failure printed, a one-line verdict, the exit code."""


def report(failures: list) -> int:
    for f in failures:
        print("FAIL", f)
    print(f"{0 if failures else 1} passed, {1 if failures else 0} failed")
    return 1 if failures else 0
