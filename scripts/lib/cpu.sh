# shellcheck shell=bash
# cpu_name: the first processor's model name from /proc/cpuinfo, followed by its family and model numbers when
# the kernel reports them (virtual machines often name every generation alike, "AMD EPYC"), as
# raylab-bench's environment line gives it.
cpu_name() {
  local field name family model
  field() { grep -m1 "^$1[[:space:]]*:" /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'; }
  name=$(field "model name")
  family=$(field "cpu family")
  model=$(field "model")
  if [ -n "$family" ] && [ -n "$model" ]; then
    echo "$name, family $family model $model"
  else
    echo "$name"
  fi
}
