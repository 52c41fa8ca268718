"""Every result number the README quotes is in the file it cites (issue 51).

The rule, kept simple on purpose:

* The README is cut into *units*: each table row, each bullet (with its continuation
  lines) and each sentence of a paragraph (split after ``.``, ``!`` or ``?`` followed by a
  space and a capital, a backtick or a parenthesis). Fenced code blocks and the whole
  "## The command line" section (commands, run-folder files, the exit-code table) are left
  out.
* A unit *cites* a file when it names a path ``benchmarks/results/X.md`` or ``docs/X.md``
  (also ``docs/design/X.md``) that exists, or a bare ``X.md`` that exists in
  ``benchmarks/results/`` or ``docs/``.
* The *numbers* of a unit are the tokens ``12``, ``0.75``, ``14/20`` (digits, an optional
  decimal part, an optional ``/denominator``), not preceded by a letter, digit, ``.``,
  ``_`` or ``@``, after removing:

  - inline code spans and Markdown link targets (option names, file names, commits);
  - identifiers: a number or list of numbers after ``Fig.``, ``Figs.``, ``Table(s)``,
    ``row(s)``, ``Sec.``, ``eq.``, ``Appendix``, ``seed(s)`` (with an optional ``>=``),
    e.g. ``Fig. 1(e)``, ``seeds 0-19``, ``rows 1-9`` (one number or one ``a-b`` range:
    in ``seeds 0-19, 50 N`` the ``50`` is still checked);
  - ``N cores`` and ``Python N.N`` (the machine, not a result).

  A range ``5-15`` is two numbers, ``5`` and ``15``.
* Check: every number of a citing unit appears in at least one of the files that unit
  cites, as a whole number: not inside a longer one (``3.8`` does not match ``3.80``,
  ``50`` does not match ``150`` or ``0.50``).
* In the "## Results" section a unit with a number must cite a file: no unsourced result.

The units outside "## Results" that cite nothing (the demo's "2 min", the robot's "16 kg")
are not checked.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
MAX_LINES = 150

_PATH = re.compile(r"(?<![\w/.-])((?:benchmarks/results/|docs/)?[\w./-]*?[\w-]+\.md)\b")
_CODE = re.compile(r"`[^`]*`")
_LINK_TARGET = re.compile(r"\]\([^)]*\)")
_ID_NUM = r"\d+[a-z]?(?:\([a-z]\))?"
_IDENTIFIER = re.compile(
    r"\b(?:Figs?\.|Tables?|rows?|Sec\.|eqs?\.|Appendix|seeds?)\s+(?:>=\s*)?"
    rf"{_ID_NUM}(?:-{_ID_NUM})?"
)
_MACHINE = re.compile(r"\b\d+ cores\b|\bPython \d+(?:\.\d+)*")
_NUMBER = re.compile(r"(?<![\w.@])\d+(?:\.\d+)?(?:/\d+)?")
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z`(])")
_BULLET = re.compile(r"^\s*[-*] ")


def units(text: str) -> list[tuple[str, str]]:
    """(section, unit text) for every checked unit of a Markdown text, in order."""
    out: list[tuple[str, str]] = []
    section = ""
    block: list[str] = []
    in_code = False

    def flush() -> None:
        if block:
            joined = " ".join(line.strip() for line in block)
            out.extend((section, s) for s in _SENTENCE_END.split(joined) if s.strip())
            block.clear()

    for line in text.splitlines():
        if line.startswith("```"):
            flush()
            in_code = not in_code
            continue
        if in_code:
            continue
        if line.startswith("#"):
            flush()
            section = line.lstrip("#").strip()
            continue
        if section == "The command line":
            continue
        if not line.strip():
            flush()
        elif line.lstrip().startswith("|"):
            flush()
            out.append((section, line.strip()))
        elif _BULLET.match(line):
            flush()
            block.append(_BULLET.sub("", line))
        else:
            block.append(line)
    flush()
    return out


def cited_files(unit: str, root: Path = ROOT) -> list[Path]:
    """The existing results or docs files a unit names."""
    found: list[Path] = []
    for name in _PATH.findall(unit):
        if name.startswith(("benchmarks/results/", "docs/")):
            candidates = [root / name]
        else:
            candidates = [d / name for d in (root / "benchmarks" / "results", root / "docs")]
        found.extend(p for p in candidates if p.is_file() and p not in found)
    return found


def numbers(unit: str) -> list[str]:
    """The number tokens of a unit after the documented exclusions."""
    text = _LINK_TARGET.sub("]", unit)
    text = _CODE.sub(" ", text)
    text = _IDENTIFIER.sub(" ", text)
    text = _MACHINE.sub(" ", text)
    return _NUMBER.findall(text)


def in_file(token: str, text: str) -> bool:
    """Whether a number token appears in a text as a whole number."""
    return re.search(rf"(?<![\d.]){re.escape(token)}(?!\.?\d)", text) is not None


def problems(readme_text: str, root: Path = ROOT) -> list[str]:
    """Every unsourced or unmatched result number of a README text."""
    found: list[str] = []
    for section, unit in units(readme_text):
        nums = numbers(unit)
        files = cited_files(unit, root)
        if not files:
            if section == "Results" and nums:
                found.append(f"unsourced numbers {nums} in: {unit}")
            continue
        texts = [p.read_text(encoding="utf-8") for p in files]
        for token in nums:
            if not any(in_file(token, t) for t in texts):
                names = [str(p.relative_to(root)) for p in files]
                found.append(f"{token} not in {names}: {unit}")
    return found


def test_readme_is_at_most_150_lines() -> None:
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_LINES, f"README.md has {n} lines, at most {MAX_LINES}"


def test_every_readme_result_number_is_in_the_file_it_cites() -> None:
    assert problems(README.read_text(encoding="utf-8")) == []


def test_the_readme_cites_results_files() -> None:
    cited = {p for _, u in units(README.read_text(encoding="utf-8")) for p in cited_files(u)}
    assert ROOT / "benchmarks" / "results" / "retime_crossing" / "README.md" in cited
    assert ROOT / "docs" / "deviations.md" in cited


def test_the_checker_flags_fabricated_and_unsourced_numbers(tmp_path: Path) -> None:
    results = tmp_path / "benchmarks" / "results"
    results.mkdir(parents=True)
    (results / "runs.md").write_text("| gaitnet | 14/20 | 0.75 m/s | 3.80x | 50 |\n")
    ok = (
        "## Results\n\n"
        "`gaitnet` is clean on 14/20 at 0.75 m/s, seeds 0-19, 3.80x faster, Fig. 1(e), 50 N "
        "(`benchmarks/results/runs.md`).\n"
    )
    assert problems(ok, tmp_path) == []
    assert problems(ok.replace("`benchmarks/results/runs.md`", "runs.md"), tmp_path) == []
    fabricated = ok.replace("14/20", "16/20")
    assert any(p.startswith("16/20 not in") for p in problems(fabricated, tmp_path))
    rounded = ok.replace("3.80x", "3.8x")
    assert any(p.startswith("3.8 not in") for p in problems(rounded, tmp_path))
    after_seeds = ok.replace("3.80x", "7.5x")
    assert any(p.startswith("7.5 not in") for p in problems(after_seeds, tmp_path))
    embedded = ok.replace("50 N", "5 N")
    assert any(p.startswith("5 not in") for p in problems(embedded, tmp_path))
    unsourced = "## Results\n\n- `gaitnet` survives 50 N forward.\n"
    assert any(p.startswith("unsourced") for p in problems(unsourced, tmp_path))
    other_sentence = ok.replace("(`benchmarks/results/runs.md`).", ". See `runs.md`.")
    assert problems(other_sentence, tmp_path) != []
    code = "## Results\n\n```bash\nmake demo  # 99 s\n```\n"
    assert problems(code, tmp_path) == []
