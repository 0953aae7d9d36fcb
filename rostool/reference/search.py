"""Ranked, typo-tolerant search over the command reference.

Tiers (higher wins): exact form > command whose words and flags all appear in the query > the book's
misspelling target > query that is the start of a command > close spelling of a whole form > words
found in keywords and descriptions.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from difflib import SequenceMatcher
from functools import lru_cache
from typing import Literal

from rostool.reference.model import Entry, Misspelling, Reference

Column = Literal["ros1", "ros2"]

EXACT = 1000.0
CODE_KEY = 950.0
FULL_COMMAND = 900.0
IDENTIFIER = 700.0
STRUCTURAL = 500.0
MISSPELLING_TARGET = 450.0
FLAG_ONLY = 400.0
PREFIX = 300.0
FUZZY_LOW, FUZZY_HIGH = 150.0, 299.0
FUZZY_MIN_RATIO = 0.75
FUZZY_TOKEN_PENALTY = 15.0
MIN_SCORE = 20.0
RELATIVE_CUTOFF = 0.25

_CODE = re.compile(r"^[A-Za-z_][\w.]*\s*\(|^[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+(?:\(\))?$")
_IDENTIFIER_QUERY = re.compile(r"^([A-Za-z_][\w.]*)(?:\(.*\))?$")
_PLACEHOLDER = re.compile(r"^[<\[({]|[<'\"]")
_PURE_PLACEHOLDER = re.compile(r"<[^>]*>(?:\.\.\.)?")
_WORD = re.compile(r"[a-z0-9_]+")
_STOPWORDS = frozenset(
    {"a", "an", "and", "are", "as", "at", "be", "by", "do", "does", "for", "from", "how", "i", "in", "is"}
    | {"it", "of", "on", "or", "the", "to", "what", "with"}
)


@dataclass(frozen=True)
class Hit:
    entry: Entry
    score: float


@dataclass(frozen=True)
class SearchResult:
    query: str
    corrected: str
    hits: tuple[Hit, ...]
    notes: tuple[str, ...]

    @property
    def entries(self) -> tuple[Entry, ...]:
        return tuple(hit.entry for hit in self.hits)


def search(
    reference: Reference,
    query: str,
    *,
    column: Column = "ros1",
    section: str | None = None,
    limit: int | None = None,
) -> SearchResult:
    """Entries matching `query`, best first, with notes for the book's misspellings found in it."""
    query = " ".join(query.split())
    notes: list[str] = []
    targets: set[str] = set()
    corrected = query
    if column == "ros1":
        corrected, applied = correct_misspellings(reference.misspellings, query)
        for misspelling, wrong, right in applied:
            notes.append(misspelling.note(wrong, right))
            targets.add(misspelling.entry)
    variants = [corrected]
    if column == "ros2" and not _is_code(corrected) and not corrected.lower().startswith("ros2"):
        variants.append(f"ros2 {corrected}")

    scored: list[tuple[float, int, Entry]] = []
    for order, entry in enumerate(reference.iter_entries()):
        if section is not None and entry.section != section:
            continue
        score = max(_score_entry(entry, variant, column) for variant in variants)
        if entry.ros1 in targets:
            score = max(score, MISSPELLING_TARGET + _word_score(entry, corrected) * 0.01)
        if score >= MIN_SCORE:
            scored.append((score, order, entry))
    scored.sort(key=lambda item: (-item[0], item[1]))
    if scored:
        cutoff = max(MIN_SCORE, scored[0][0] * RELATIVE_CUTOFF)
        scored = [item for item in scored if item[0] >= cutoff]
    if limit:
        scored = scored[:limit]
    hits = tuple(Hit(entry, round(score, 2)) for score, _order, entry in scored)
    return SearchResult(query=query, corrected=corrected, hits=hits, notes=tuple(notes))


def correct_misspellings(
    misspellings: Sequence[Misspelling], query: str
) -> tuple[str, list[tuple[Misspelling, str, str]]]:
    """Rewrite the book's wrong forms in `query`; returns the new query and (misspelling, found, fix)."""
    applied: list[tuple[Misspelling, str, str]] = []
    commands = sorted(
        (m for m in misspellings if m.kind == "command"),
        key=lambda m: (m.match is not None, -len(m.wrong.split())),
    )
    for misspelling in commands:
        rewritten = _rewrite_command(misspelling, query)
        if rewritten is not None:
            found, fix, query = rewritten
            applied.append((misspelling, found, fix))
            break
    names = sorted((m for m in misspellings if m.kind == "name"), key=lambda m: -len(m.wrong))
    for misspelling in names:
        if misspelling.wrong in query:
            query = query.replace(misspelling.wrong, misspelling.right)
            applied.append((misspelling, misspelling.wrong, misspelling.right))
    return query, applied


def _rewrite_command(misspelling: Misspelling, query: str) -> tuple[str, str, str] | None:
    if misspelling.match is not None:
        found = misspelling.match.match(query)
        if found is None:
            return None
        fix = found.expand(misspelling.right)
        return found.group(0), fix, fix + query[found.end() :]
    wrong = misspelling.wrong.split()
    words = query.split()
    if [w.lower() for w in words[: len(wrong)]] != [w.lower() for w in wrong]:
        return None
    rest = words[len(wrong) :]
    return " ".join(words[: len(wrong)]), misspelling.right, " ".join([misspelling.right, *rest])


def _forms(entry: Entry, column: Column) -> list[tuple[str, float, bool]]:
    """(text, score offset, counts for identifier matching) of the forms a query is compared with."""
    rostool = [(form, -60.0, False) for form in entry.rostool_forms]
    if column == "ros2":
        return ([(entry.ros2, 0.0, True)] if entry.ros2 else []) + rostool
    forms = [(entry.ros1, 0.0, True)]
    forms += [(alias, -5.0, True) for alias in entry.aliases]
    forms += rostool
    if entry.ros2:
        forms.append((entry.ros2, -80.0, False))
    return forms


def _score_entry(entry: Entry, query: str, column: Column) -> float:
    best = 0.0
    query_norm = query.lower()
    query_code = _is_code(query)
    query_tokens = tuple(query.split())
    identifier = _identifier(query)
    code_like = identifier is not None and bool(re.search(r"[._(]", query))
    for text, offset, own in _forms(entry, column):
        best = max(
            best, _score_form(text, offset, own, query_norm, query_code, query_tokens, identifier, code_like)
        )
    words = _word_score(entry, query)
    if best > 0:
        return best + min(words, 99.0) * 0.05
    return min(words, FUZZY_LOW - 1)


def _score_form(
    text: str,
    offset: float,
    own: bool,
    query_norm: str,
    query_code: bool,
    query_tokens: tuple[str, ...],
    identifier: str | None,
    code_like: bool,
) -> float:
    text_norm = text.lower()
    if query_norm == text_norm:
        return EXACT + offset
    form_code = _is_code(text)
    best = 0.0
    if form_code and query_code and _code_key(query_norm) == _code_key(text_norm):
        best = CODE_KEY + offset
    # A bare word (`feedback`) names a function only by the called name, never by an argument in it:
    # else `publish_feedback(feedback)` would outrank every command that is about feedback.
    named = text_norm if code_like else _code_key(text_norm)
    if identifier and (code_like or (own and form_code)) and _contains_identifier(named, identifier):
        best = max(best, IDENTIFIER + offset)
    if not form_code and not query_code:
        key = command_key(text)
        structural = _structural(key, query_tokens)
        if structural:
            # Among commands with the same literal part, prefer the one whose arguments fit the query.
            shape = _argument_shape(text.split()[len(key) :], query_tokens[len(key) :])
            best = max(best, structural + offset + shape + 2 * _ratio(query_norm, text_norm))
    key_text = _code_key(text_norm) if form_code else " ".join(command_key(text)).lower()
    ratio = max(
        _similar(query_norm, key_text, FUZZY_MIN_RATIO), _similar(query_norm, text_norm, FUZZY_MIN_RATIO)
    )
    if ratio >= FUZZY_MIN_RATIO:
        fuzzy = FUZZY_LOW + (FUZZY_HIGH - FUZZY_LOW) * (ratio - FUZZY_MIN_RATIO) / (1 - FUZZY_MIN_RATIO)
        best = max(best, fuzzy + offset)
    return max(best, 0.0)


def _structural(key: tuple[str, ...], query: tuple[str, ...]) -> float:
    """How well the command `key` (words then flags, no arguments) fits the query's tokens."""
    if not key or not query:
        return 0.0
    key_words = [token for token in key if not _is_flag(token)]
    key_flags = {token for token in key if _is_flag(token)}
    query_words = [token for token in query if not _is_flag(token)]
    query_flags = {token for token in query if _is_flag(token)}
    if not query_words:
        if query_flags and key_flags and query_flags <= key_flags:
            return FLAG_ONLY + 5 * len(query_flags)
        return 0.0
    fuzzy = _match_words(key_words, query_words)
    if fuzzy is not None and key_flags <= query_flags:
        if len(query) == len(key) and query_flags == key_flags:
            return FULL_COMMAND - FUZZY_TOKEN_PENALTY * fuzzy
        extra_flags = len(query_flags - key_flags)
        return STRUCTURAL + 10 * len(key) - FUZZY_TOKEN_PENALTY * fuzzy - 3 * extra_flags
    if len(query) < len(key):
        prefix_fuzzy = 0
        for query_token, key_token in zip(query, key, strict=False):
            closeness = _token_closeness(query_token, key_token)
            if closeness is None:
                return 0.0
            prefix_fuzzy += closeness
        return PREFIX + 10 * len(query) - FUZZY_TOKEN_PENALTY * prefix_fuzzy
    return 0.0


def _argument_shape(form_args: Sequence[str], query_args: Sequence[str]) -> float:
    """+4/-4 per argument with fixed text around its placeholder (`<action>/goal`) that the query
    does / does not fill in."""
    score = 0.0
    for form_arg in form_args:
        if _PURE_PLACEHOLDER.fullmatch(form_arg) or "<" not in form_arg:
            continue
        pattern = re.compile(
            "".join(
                r"\S+" if part.startswith("<") else re.escape(part)
                for part in re.split(r"(<[^>]*>)", form_arg)
            )
            + "$",
            re.IGNORECASE,
        )
        score += 4.0 if any(pattern.match(arg) for arg in query_args) else -4.0
    return score


def _match_words(key_words: Sequence[str], query_words: Sequence[str]) -> int | None:
    """Number of fuzzy (not exact) word matches if the key's words start the query, else None."""
    if len(query_words) < len(key_words):
        return None
    fuzzy = 0
    for key_word, query_word in zip(key_words, query_words, strict=False):
        closeness = _token_closeness(query_word, key_word)
        if closeness is None:
            return None
        fuzzy += closeness
    return fuzzy


def _token_closeness(a: str, b: str) -> int | None:
    """0 if equal, 1 if a small typo apart, None otherwise. Flags and names must match exactly."""
    if a == b or (not _is_flag(a) and a.lower() == b.lower()):
        return 0
    if a[:1] in "-/" or b[:1] in "-/":
        return None
    a, b = a.lower(), b.lower()
    longest = max(len(a), len(b))
    allowed = 0 if longest <= 3 else 1 if longest <= 7 else 2
    if abs(len(a) - len(b)) > allowed:
        return None
    return 1 if 0 < edit_distance(a, b) <= allowed else None


def edit_distance(a: str, b: str) -> int:
    """Optimal string alignment distance: insertions, deletions, substitutions, adjacent swaps."""
    previous_previous: list[int] = []
    previous = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        current = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = 0 if a[i - 1] == b[j - 1] else 1
            current[j] = min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                current[j] = min(current[j], previous_previous[j - 2] + 1)
        previous_previous, previous = previous, current
    return previous[len(b)]


def command_key(text: str) -> tuple[str, ...]:
    """The literal part of a command form: its words and flags before the first argument placeholder."""
    tokens: list[str] = []
    for token in text.split():
        if _PLACEHOLDER.search(token):
            break
        tokens.append(token)
    return tuple(tokens)


def _code_key(text: str) -> str:
    """`rospy.Publisher(topic, ...)` -> `rospy.publisher`; keeps chained calls like `a().b`."""
    first = text.split(";")[0].strip()
    previous = None
    while previous != first:
        previous = first
        first = re.sub(r"\([^()]*\)", "()", first)
    return first.removesuffix("()").lower()


def _is_code(text: str) -> bool:
    return bool(_CODE.match(text.strip()))


def _is_flag(token: str) -> bool:
    return len(token) > 1 and token.startswith("-")


def _identifier(query: str) -> str | None:
    found = _IDENTIFIER_QUERY.match(query.strip())
    return found.group(1).lower() if found else None


def _contains_identifier(text: str, identifier: str) -> bool:
    return re.search(rf"(?<!\w){re.escape(identifier)}(?!\w)", text) is not None


def _ratio(a: str, b: str) -> float:
    if not a or not b:
        return 0.0
    return SequenceMatcher(None, a, b).ratio()


def _similar(a: str, b: str, cutoff: float) -> float:
    """difflib's ratio when it can reach `cutoff`, else 0 (cheap length test first)."""
    if not a or not b or 2 * min(len(a), len(b)) / (len(a) + len(b)) < cutoff:
        return 0.0
    matcher = SequenceMatcher(None, a, b)
    if matcher.quick_ratio() < cutoff:
        return 0.0
    return matcher.ratio()


def _word_score(entry: Entry, query: str) -> float:
    fields = _entry_words(entry)
    total = 0.0
    for word in _query_words(query):
        total += max(_word_in(word, words, weight) for words, weight in fields)
    return total


def _query_words(query: str) -> list[str]:
    return [word for word in _WORD.findall(query.lower()) if word not in _STOPWORDS and len(word) > 1]


@lru_cache(maxsize=512)
def _entry_words(entry: Entry) -> tuple[tuple[frozenset[str], float], ...]:
    forms = " ".join(filter(None, (entry.ros1, *entry.aliases, entry.ros2, *entry.rostool_forms)))
    return (
        (_words(entry.keywords), 60.0),
        (_words([forms]), 30.0),
        (_words([entry.description]), 25.0),
        (_words([entry.inputs, entry.output]), 10.0),
    )


def _words(texts: Iterable[str]) -> frozenset[str]:
    found: set[str] = set()
    for text in texts:
        for word in _WORD.findall(text.lower()):
            found.add(word)
            found.update(part for part in word.split("_") if len(part) > 1)
    return frozenset(found)


def _word_in(word: str, words: frozenset[str], weight: float) -> float:
    if word in words:
        return weight
    if len(word) >= 4 and any(candidate.startswith(word) for candidate in words):
        return weight * 0.8
    if len(word) >= 4 and any(_similar(word, candidate, 0.85) for candidate in words):
        return weight * 0.6
    return 0.0
