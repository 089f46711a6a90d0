"""Who may call the coordinator: yarfd's tokens file, roles and job ownership.

The rules are yarfd's (server/src/service/token_auth.cc, access.cc), so
one tokens file serves both: one ``TOKEN USER ROLE`` per line, ``#``
starts a comment, ROLE is ``submit`` (submits jobs, acts on its own) or
``admin`` (acts on every job). Without tokens every caller is the local
admin, as on a yarfd on loopback.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path


class AccessError(Exception):
    """A tokens file, certificate or listen address the coordinator cannot start with."""


class Role(Enum):
    SUBMIT = "submit"
    ADMIN = "admin"


@dataclass(frozen=True)
class Caller:
    user: str
    role: Role


LOCAL_ADMIN = Caller("local", Role.ADMIN)

TokenTable = dict[str, Caller]


def read_token_file(path: Path) -> TokenTable:
    """The tokens of ``path``; errors name the line, never the token on it."""
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError):
        raise AccessError(f"cannot read the tokens file {path}") from None
    tokens: TokenTable = {}
    for number, line in enumerate(text.splitlines(), 1):
        where = f"{path} line {number}"
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue  # blank or a comment
        if len(fields) != 3:
            raise AccessError(
                f"{where}: expected `TOKEN USER ROLE` (three fields separated by spaces)"
            )
        token, user, role_name = fields
        try:
            role = Role(role_name)
        except ValueError:
            raise AccessError(f"{where}: role '{role_name}' is neither submit nor admin") from None
        if token in tokens:
            raise AccessError(f"{where}: this token is already given to {tokens[token].user}")
        tokens[token] = Caller(user, role)
    if not tokens:
        raise AccessError(f"the tokens file {path} holds no token")
    return tokens


def may_act_on(caller: Caller, owner: str) -> bool:
    """Whether ``caller`` may see and act on a job submitted by ``owner``."""
    return caller.role is Role.ADMIN or caller.user == owner
