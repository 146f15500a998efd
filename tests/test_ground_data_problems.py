from ground.data.problems import Problem, count_levels, has_errors


def test_str_and_counts():
    problems = [Problem("a.txt:3", "class id 9 out of range"), Problem("b.jpg", "negative", "info")]
    assert str(problems[0]) == "a.txt:3: class id 9 out of range"
    assert count_levels(problems) == {"error": 1, "warning": 0, "info": 1}
    assert has_errors(problems) and not has_errors(problems[1:])
    assert problems[1].to_dict() == {"path": "b.jpg", "reason": "negative", "level": "info"}
