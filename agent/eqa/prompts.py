"""The prompts of Explore until Confident (§III, §V), and reading them back.

Prompts are plain text so any VLM backend can take them; the simulator reads the question and the
choices back out of the same text, as a real model would.
"""

from __future__ import annotations

import re

from worlds.bus.questions import LETTERS

ANSWER_SUFFIX = "Answer with the option's letter from the given choices directly."
RELEVANCE_TEMPLATE = (
    "Consider the question: '{question}'. Are you confident about answering the question with the "
    "current view? Answer with Yes or No."
)
LSV_TEMPLATE = (
    "Consider the question: '{question}', and you will explore the environment for answering it. "
    "Which direction (black letters on the image) would you explore then? Answer with a single letter."
)
GSV_TEMPLATE = (
    "Consider the question: '{question}', and you will explore the environment for answering it. "
    "Is there any direction shown in the image worth exploring? Answer with Yes or No."
)
YES_NO = ("Yes", "No")

_CHOICE_LINE = re.compile(r"^([A-D])\. (.*)$")
_QUOTED = re.compile(r"Consider the question: '(.*)'[.,]")


def answer_prompt(question: str, choices: list[str]) -> str:
    """The paper's answer prompt: the question, its lettered choices, and the instruction to answer with a letter.

    Args:
        question: the question.
        choices: the choices, lettered in order.

    Returns:
        The prompt.
    """
    lines = [question] + [f"{letter}. {choice}" for letter, choice in zip(LETTERS, choices)]
    return "\n".join(lines + [ANSWER_SUFFIX])


def relevance_prompt(question: str) -> str:
    """The paper's prompt asking whether the view helps answer the question.

    Args:
        question: the question.

    Returns:
        The prompt.
    """
    return RELEVANCE_TEMPLATE.format(question=question)


def lsv_prompt(question: str) -> str:
    """The paper's local semantic value prompt: where in the view to look next for the answer.

    Args:
        question: the question.

    Returns:
        The prompt.
    """
    return LSV_TEMPLATE.format(question=question)


def gsv_prompt(question: str) -> str:
    """The paper's global semantic value prompt: whether the view's direction is worth exploring.

    Args:
        question: the question.

    Returns:
        The prompt.
    """
    return GSV_TEMPLATE.format(question=question)


def prompt_kind(prompt: str) -> str:
    """Which of the paper's prompts this is: answer, relevance, lsv, gsv, or other.

    Args:
        prompt: a prompt's text.

    Returns:
        The kind.
    """
    if read_answer_prompt(prompt) is not None:
        return "answer"
    for kind, template in (("relevance", RELEVANCE_TEMPLATE), ("lsv", LSV_TEMPLATE), ("gsv", GSV_TEMPLATE)):
        tail = template.split("{question}")[1]
        if prompt.startswith("Consider the question: '") and prompt.endswith(tail):
            return kind
    return "other"


def read_answer_prompt(prompt: str) -> tuple[str, dict[str, str]] | None:
    """(question, {letter: choice}) from an answer prompt, None if it is not one.

    Args:
        prompt: a prompt's text.

    Returns:
        The question and its choices by letter, or None.
    """
    lines = prompt.strip().split("\n")
    if len(lines) < 3 or lines[-1] != ANSWER_SUFFIX:
        return None
    choices = {}
    for line in lines[1:-1]:
        match = _CHOICE_LINE.match(line)
        if not match:
            return None
        choices[match.group(1)] = match.group(2)
    return lines[0], choices


def read_quoted_question(prompt: str) -> str | None:
    """The question inside "Consider the question: '...'" prompts.

    Args:
        prompt: a prompt's text.

    Returns:
        The question, or None when the prompt quotes none.
    """
    match = _QUOTED.search(prompt)
    return match.group(1) if match else None
