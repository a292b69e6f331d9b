"""The README documents every command and every option (as sqlite-utils' docs tests do): a new
option that nobody wrote down fails here, not in a user's hands."""

from __future__ import annotations

import pytest
from conftest import ROOT

from massprops.cli import cli

README = (ROOT / "README.md").read_text()


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_every_command_and_option_is_in_the_readme(name):
    command = cli.commands[name]
    assert f"massprops {name}" in README
    missing = [opt for param in command.params for opt in param.opts
               if opt.startswith("--") and opt not in README and opt != "--help"]
    assert missing == []


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_every_command_and_option_has_help(name):
    command = cli.commands[name]
    assert command.help
    assert all(param.help for param in command.params if hasattr(param, "help")
               and param.param_type_name == "option")
