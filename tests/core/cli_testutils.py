"""Shared checks of the CLI tests."""


def one_line_error(capsys, *parts):
    """The CLI's error: one line on stderr, no traceback, naming each of ``parts``."""
    err = capsys.readouterr().err
    assert err.startswith("darboux-cli: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    for part in parts:
        assert part in err, err
    return err
