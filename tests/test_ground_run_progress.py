from ground.run.progress import progress


def test_progress_yields_everything_and_is_silent_off_a_terminal(capsys):
    assert list(progress(range(500), desc="x")) == list(range(500))
    assert list(progress(iter([1, 2, 3]), total=3)) == [1, 2, 3]
    assert capsys.readouterr().err == ""  # pytest's stderr is not a TTY: no bar in logs
