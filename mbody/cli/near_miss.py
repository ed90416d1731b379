"""What a command line's leftover words were probably meant to be: a misspelt option
(``--t_end`` for ``--t-end``, ``--know`` for ``--known``), an option of another command,
or one positional argument too many. `mbody.cli.app` adds this to argparse's
"unrecognized arguments" so that the message says what was expected, not only what was
refused."""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping, Sequence

from mbody.errors import closest

_NUMBER = re.compile(r"-\.?\d")
"""A leading minus before a digit is a negative number (a value), not an option."""


def option_like(word: str) -> bool:
    """Whether argparse would read `word` as an option string rather than a value."""
    return (len(word) > 1 and word.startswith("-") and word != "--"
            and not _NUMBER.match(word) and " " not in word)


def unknown_options(command: argparse.ArgumentParser, words: Sequence[str]) -> list[str]:
    """The words before ``--`` in `words` that look like options `command` does not have
    (``--name=value`` and ``-ovalue`` are its own ``--name`` and ``-o``)."""
    known = command._option_string_actions
    return [w for w in option_words(words) if w.split("=", 1)[0] not in known
            and not (w[1] != "-" and w[:2] in known)]


def option_words(words: Sequence[str]) -> list[str]:
    """The words before ``--`` in `words` that argparse reads as option strings."""
    out = []
    for word in words:
        if word == "--":
            break
        if option_like(word):
            out.append(word)
    return out


def options_hint(command_name: str, command: argparse.ArgumentParser,
                 options: Sequence[str], commands: Mapping[str, argparse.ArgumentParser]
                 ) -> str:
    """`option_hint` of each of `options` (named when there are several), or where the
    options are listed when none has one."""
    hints = [(w, option_hint(command_name, command, w, commands)) for w in options]
    found = [f"{w.split('=', 1)[0]}: {h}" if len(options) > 1 else h for w, h in hints if h]
    if found:
        return "; ".join(found)
    return f"mbody {command_name + ' ' if command_name else ''}--help lists the options"


def option_hint(command_name: str, command: argparse.ArgumentParser, word: str,
                commands: Mapping[str, argparse.ArgumentParser]) -> str:
    """For an unknown option string `word` of `command`: the closest of its own options
    (`mbody.errors.closest`; an underscore is read as a hyphen), else the other commands
    that have exactly that option, else ''. `command_name` '' is `mbody` itself, before
    any command, and one of `command`'s own options unrecognized was given there."""
    name = word.split("=", 1)[0]
    spelt = name.replace("_", "-")
    if name in command._option_string_actions:  # `mbody --t-end=3 simulate MODEL`
        return f"{name} goes after the command: mbody {command_name} ... {word}"
    # compared without their dashes: every long option shares '--', which alone makes
    # '--zqxw' "close" to '--q'; a long option is preferred to a short one of one letter
    options = sorted(command._option_string_actions, key=lambda o: not o.startswith("--"))
    bare: dict[str, str] = {}
    for option in options:
        bare.setdefault(option.lstrip("-"), option)
    meant = closest(spelt.lstrip("-"), bare)
    if meant is not None:
        return f"did you mean '{bare[meant]}'?"
    others = [c for c, p in commands.items()
              if c != command_name and spelt in p._option_string_actions]
    owners = ("every command" if len(others) > 1 and len(others) == len(commands)
              else ", ".join(others))
    if others and command_name:
        return f"{spelt} is an option of {owners}, not of {command_name}"
    if others:
        return f"{spelt} is an option of {owners}; it goes after the command"
    return ""


_UNIT = re.compile(r"[A-Za-z][A-Za-z/^²³]*(:.*)?")
"""A unit after a number: 'rpm', 'rev', 'deg/s'; in a sweep's range, 'rpm:1200'."""


def split_value(command: argparse.ArgumentParser, words: Sequence[str],
                extras: Sequence[str]) -> str:
    """A hint when leftovers are the rest of an option's value split by the shell at a
    space before a unit (``--t-end 1 rev``, ``--set drivers.motor.speed=600 rpm``,
    ``--set PATH=300 rpm:1200 rpm:4``), else ''."""
    for i in range(2, len(words)):
        action = command._option_string_actions.get(words[i - 2])
        if (words[i] in extras and _UNIT.fullmatch(words[i]) and words[i - 1][-1:].isdigit()
                and action is not None and action.nargs is None and action.option_strings):
            j = i + 1
            while (j < len(words) and ":" in words[j - 1] and words[j] in extras
                   and not option_like(words[j])):  # a range goes on: 'rpm:1200 rpm:4'
                j += 1
            option, quoted = words[i - 2], " ".join(words[i - 1:j])
            return (unit_refused(action, option, quoted) or "a value with a space is one "
                    f"argument: quote it, {option} '{quoted}'")
    return ""


def unit_refused(action: argparse.Action, option: str, quoted: str) -> str:
    """Why `option`'s value `quoted` (a number and its unit, which the shell split) would
    be refused even quoted, and what to write instead; '' when it may be accepted (the
    option's type takes it, or a --set path's key reads that unit: ``'600 rpm'`` as a
    driver's speed). A --set or --known value is given in SI units without its unit
    (`mbody.model.values.unit_refused`, `mbody.model.arguments.known_unit_refused`)."""
    if callable(action.type):
        try:
            action.type(quoted)
        except (argparse.ArgumentTypeError, ValueError) as exc:
            return f"quoted, {option} '{quoted}' is refused too: {exc}"
        return ""
    name, sep, value = quoted.partition("=")
    if not sep or option not in ("--set", "--known"):
        return ""
    if option == "--set":
        from mbody.model.values import unit_refused as refused_at_key

        refused = refused_at_key(name, value)
    else:
        from mbody.model.arguments import known_unit, known_unit_refused

        refused = known_unit_refused(name, value)
        if refused is not None:
            refused = (f"takes no unit ({refused[0]}; values are in {known_unit(name)})",
                       refused[1])
    if refused is None:
        return ""
    hint, meant = refused
    return (f"{name} {hint}"
            + (f": write {option} {name}={meant}" if meant is not None else ""))


def unrecognized_message(command_name: str, command: argparse.ArgumentParser,
                         extras: Sequence[str],
                         commands: Mapping[str, argparse.ArgumentParser],
                         words: Sequence[str] = ()) -> str:
    """argparse's "unrecognized arguments: ..." with what each was probably meant to be:
    a did-you-mean for a misspelt option, or, when every leftover is a positional word,
    the quotes a value with a space needs (`split_value`, from the command's `words`),
    or how many positional arguments the command takes."""
    message = f"unrecognized arguments: {' '.join(extras)}"
    options = option_words(extras)  # argparse left them: unknown, or before the command
    if options:
        return f"{message}; {options_hint(command_name, command, options, commands)}"
    takes = [str(a.metavar or a.dest) for a in command._get_positional_actions()
             if a.nargs != argparse.PARSER]
    extra = [w for w in extras if w != "--"]
    quote = split_value(command, words, extra)
    if quote:
        return f"{message}; {quote}"
    if takes and extra:
        n = len(extra)
        many = "one argument" if n == 1 else f"{n} arguments"
        return (f"{message}; {command_name or 'mbody'} takes {' '.join(takes)} "
                f"(and options), so {many} too many")
    return message
