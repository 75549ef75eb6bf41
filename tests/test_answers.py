"""The answer log's fallback rule, and writing and reading back the EQA prompts."""

from __future__ import annotations

import pytest

from agent.eqa.answers import AnswerLog, StepScores
from agent.eqa.prompts import (
    ANSWER_SUFFIX,
    YES_NO,
    answer_prompt,
    read_answer_prompt,
    read_quoted_question,
    relevance_prompt,
)
from worlds.bus.questions import PAD_CHOICE


def test_add_numbers_steps_from_one_and_copies_scores() -> None:
    log = AnswerLog()
    probs = {"A": 0.7, "B": 0.3}
    first = log.add(probs, 0.4)
    probs["A"] = 0.0  # the log keeps its own copy
    second = log.add({"A": 0.1, "B": 0.9}, 1)
    assert (first.step, second.step) == (1, 2)
    assert len(log) == 2 and log.steps == [first, second]
    assert first.answer_probs == {"A": 0.7, "B": 0.3}
    assert isinstance(second.relevance, float)


def test_best_is_the_argmax() -> None:
    assert StepScores(1, {"A": 0.1, "B": 0.6, "C": 0.3}, 0.5).best() == "B"


def test_fallback_is_the_most_relevant_step_and_its_argmax() -> None:
    log = AnswerLog()
    log.add({"A": 0.9, "B": 0.05, "C": 0.05}, 0.2)  # confident, but irrelevant
    log.add({"A": 0.2, "B": 0.1, "C": 0.7}, 0.8)  # the most relevant view
    log.add({"A": 0.1, "B": 0.8, "C": 0.1}, 0.5)
    chosen = log.fallback()
    assert chosen.step == 2
    assert chosen.best() == "C"


def test_fallback_takes_the_earliest_on_ties() -> None:
    log = AnswerLog()
    log.add({"A": 0.6, "B": 0.4}, 0.3)
    log.add({"A": 0.2, "B": 0.8}, 0.7)
    log.add({"A": 0.9, "B": 0.1}, 0.7)
    log.add({"A": 0.5, "B": 0.5}, 0.7)
    assert log.fallback().step == 2
    assert log.fallback().best() == "B"


def test_fallback_of_an_empty_log_raises() -> None:
    with pytest.raises(ValueError, match="no step has been scored"):
        AnswerLog().fallback()


def test_answer_prompt_round_trip() -> None:
    question = "What colour is the mug in the kitchen?"
    choices = ["red", "living room", PAD_CHOICE, "A. tricky"]
    prompt = answer_prompt(question, choices)
    assert prompt.splitlines()[0] == question
    assert prompt.splitlines()[-1] == ANSWER_SUFFIX
    assert "B. living room" in prompt
    assert read_answer_prompt(prompt) == (question, {"A": "red", "B": "living room", "C": PAD_CHOICE, "D": "A. tricky"})
    # surrounding whitespace does not matter
    assert read_answer_prompt("\n" + prompt + "\n  ") == read_answer_prompt(prompt)


def test_answer_prompt_with_two_choices() -> None:
    prompt = answer_prompt("Is there a red mug in the kitchen?", ["yes", "no"])
    assert read_answer_prompt(prompt) == ("Is there a red mug in the kitchen?", {"A": "yes", "B": "no"})


def test_relevance_prompt_round_trip() -> None:
    for question in ("Which room is the red mug in?", "What colour is the mug in the kitchen?",
                     "Is there a book in the living room's corner?"):
        prompt = relevance_prompt(question)
        assert question in prompt and "Yes or No" in prompt
        assert read_quoted_question(prompt) == question
    assert YES_NO == ("Yes", "No")


@pytest.mark.parametrize(
    "text",
    [
        "",
        "What colour is the mug?",
        "What colour is the mug?\n" + ANSWER_SUFFIX,  # no choices
        "What colour is the mug?\nA. red\nB. blue",  # no suffix
        "What colour is the mug?\nA. red\nE. blue\n" + ANSWER_SUFFIX,  # E is not a letter
        "What colour is the mug?\nA) red\n" + ANSWER_SUFFIX,
        "What colour is the mug?\nA. red\nsome remark\n" + ANSWER_SUFFIX,
        relevance_prompt("What colour is the mug in the kitchen?"),
    ],
)
def test_non_answer_prompts_give_none(text: str) -> None:
    assert read_answer_prompt(text) is None


@pytest.mark.parametrize(
    "text",
    ["", "Answer with Yes or No.", "Consider the question: What colour?",
     answer_prompt("What colour is the mug in the kitchen?", ["red", "blue"])],
)
def test_non_relevance_prompts_give_none(text: str) -> None:
    assert read_quoted_question(text) is None
