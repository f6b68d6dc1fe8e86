# bash completion for combabc (installed to share/bash-completion/completions/combabc): the
# commands, each command's options, and files: .toml configs, .sqlite histories, .csv profiles,
# directories for -o. Needs only bash (compgen); tests/packaging/cli_docs_test.sh keeps it in step
# with `combabc <command> --help`.
_combabc() {
  local cur prev cmd i
  cur=${COMP_WORDS[COMP_CWORD]}
  prev=${COMP_WORDS[COMP_CWORD - 1]}
  local commands="run resume enumerate design simulate report export verify"
  cmd=""
  for ((i = 1; i < COMP_CWORD; i++)); do
    case " $commands " in *" ${COMP_WORDS[i]} "*) cmd=${COMP_WORDS[i]}; break ;; esac
  done
  local opts files
  case $cmd in
    run)
      opts="-h --help -o --output -j --threads --overwrite --from --no-report -q --quiet
            --no-cache"
      files=toml ;;
    resume)
      opts="-h --help -j --threads --max-simulations --max-wall-time --min-acceptance-rate
            --max-failure-fraction --waves --no-report -q --quiet --no-cache"
      files=sqlite ;;
    enumerate)
      opts="-h --help --threshold -o --output -j --threads --overwrite --top --no-report -q --quiet
            --no-cache"
      files=toml ;;
    design)
      opts="-h --help --posterior -o --output -j --threads --overwrite --no-figure --no-cache"
      files=toml ;;
    simulate) opts="-h --help --clamps -o --output --overwrite --low-fidelity --no-cache"; files=toml ;;
    report) opts="-h --help -o --output --overwrite"; files=sqlite ;;
    export) opts="-h --help -o --output --overwrite --no-netcdf --all-waves"; files=sqlite ;;
    verify) opts="-h --help"; files=sqlite ;;
    *)
      mapfile -t COMPREPLY < <(compgen -W "$commands -h --help --version" -- "$cur")
      return ;;
  esac
  case $prev in
    -o | --output)
      if [[ $cmd == simulate ]]; then
        mapfile -t COMPREPLY < <(compgen -f -X '!*.csv' -- "$cur"; compgen -d -- "$cur")
      else
        mapfile -t COMPREPLY < <(compgen -d -- "$cur")
      fi
      return ;;
    # A finished run's history: run --from, design --posterior.
    --from | --posterior)
      mapfile -t COMPREPLY < <(compgen -f -X '!*.sqlite' -- "$cur"; compgen -d -- "$cur")
      return ;;
    -j | --threads | --threshold | --top | --clamps | --max-*| --min-*) COMPREPLY=(); return ;;
  esac
  if [[ $cur == -* ]]; then
    mapfile -t COMPREPLY < <(compgen -W "$opts" -- "$cur")
  else
    mapfile -t COMPREPLY < <(compgen -f -X "!*.$files" -- "$cur"; compgen -d -- "$cur")
  fi
}
complete -o filenames -F _combabc combabc
