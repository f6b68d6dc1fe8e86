#!/usr/bin/env bash
# The man page and the bash completion cannot drift from the CLI: every command of
# `combabc --help`, and every option of `combabc <command> --help`, must be in the man page's
# COMMANDS entry of that command (or, for an option shared with run, named there) and in the
# completion's case for that command; and the completion must complete a command, an option and
# a config file.  Usage: cli_docs_test.sh COMBABC MAN_PAGE COMPLETION
set -euo pipefail
combabc=$1 page=$2 completion=$(realpath "$3")
fail=0
problem() { echo "FAIL: $*"; fail=1; }

# Options of a help text: the -x / --long names at the start of its lines.
options_of() {
  "$combabc" "$@" --help | sed -n '/^Options:/,/^$/p' |
    grep -oE '^  (-[A-Za-z0-9]|--[a-z][-a-z]*)(,--[a-z][-a-z]*)?' | tr ',' '\n' | tr -d ' '
}
commands=$("$combabc" --help | sed -n '/^Subcommands:/,/^$/p' | awk 'NR > 1 && NF {print $1}')
[ -n "$commands" ] || problem "no commands parsed from combabc --help"
# The page with roff's \- as -, and the COMMANDS section cut into one block per command.
text=$(sed 's/\\-/-/g' "$page")
section=$(sed -n '/^\.SH COMMANDS/,/^\.SH /p' <<<"$text")
for option in $(options_of); do
  grep -qe "$option" <<<"$(sed -n '/^\.SH OPTIONS/,/^\.SH /p' <<<"$text")" ||
    problem "combabc $option is not in the man page's OPTIONS"
done
for cmd in $commands; do
  # From the .TP whose tag is ".B <cmd> ..." to the next command's .TP.
  block=$(awk -v c="$cmd" 'prev == ".TP" && /^\.B [a-z]+ / { in_block = ($2 == c) }
                           in_block { print } { prev = $0 }' <<<"$section")
  [ -n "$block" ] || { problem "command '$cmd' has no entry in the man page's COMMANDS"; continue; }
  grep -qE "^\.B combabc $cmd( |$)" <<<"$text" || problem "command '$cmd' is not in the SYNOPSIS"
  # The completion's case for it, from its pattern to its ";;".
  case_line=$(awk -v c="$cmd" '!in_case && $0 ~ "^ *([a-z]+ [|] )*" c "( [|] [a-z]+)*[)]" { in_case = 1 }
                               in_case { printf "%s ", $0; if (/;;/) exit }' "$completion")
  [ -n "$case_line" ] || problem "command '$cmd' has no case in the completion"
  for option in $(options_of "$cmd" | grep -vxE -- '-h|--help'); do
    grep -qe "$option\\b" <<<"$block" || problem "combabc $cmd $option is not in its man page entry"
    grep -qe " $option[ \"]" <<<"$case_line" ||
      problem "combabc $cmd $option is not in the completion"
  done
done

# The completion itself, in a clean bash.
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
touch "$dir/a.toml" "$dir/b.sqlite" "$dir/c.txt"
got=$(cd "$dir" && bash -c 'source "$1"
  complete() { COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); _combabc; echo "${COMPREPLY[*]}"; }
  complete combabc re; complete combabc run --no; complete combabc run ""; complete combabc report ""' _ "$completion")
expected=$'resume report\n--no-report --no-cache\na.toml\nb.sqlite'
[ "$got" = "$expected" ] || problem "completion gave [$got], expected [$expected]"
if ((fail)); then exit 1; fi
echo "man page and completion cover $(wc -w <<<"$commands") commands and their options"
