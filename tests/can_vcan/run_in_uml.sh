#!/bin/sh
# Runs a test script inside Debian's user-mode-linux (a real Linux kernel with vcan; the host's
# kernel has no AF_CAN): one boot, the host's / as the root file system (hostfs), modules can,
# can_raw, can_bcm, vcan loaded, vcan0 to vcan3 up. The script's exit code is ours.
# Usage: run_in_uml.sh WORK_DIR SCRIPT [NAME=value ...]   (the names become the script's environment)
# Fails (never skips) when user-mode-linux, kmod or the kernel modules are missing.
set -u
work=$1; script=$2; shift 2
uml=$(command -v linux.uml || true)
if [ -z "$uml" ]; then echo "run_in_uml: linux.uml not found: apt-get install user-mode-linux kmod can-utils python3-can" >&2; exit 1; fi
if ! command -v insmod >/dev/null 2>&1 && [ ! -x /usr/sbin/insmod ] && [ ! -x /sbin/insmod ]; then
  echo "run_in_uml: insmod not found: apt-get install kmod" >&2; exit 1
fi
mkdir -p "$work" || exit 1
work=$(cd "$work" && pwd)
rm -f "$work/rc" "$work/out"
cat > "$work/init" <<'INIT'
#!/bin/sh
# PID 1 of the UML guest: must never exit (the kernel would panic without leaving an rc).
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
mount -t proc proc /proc; mount -t sysfs sys /sys
M=/usr/lib/uml/modules/$(uname -r)/kernel
(
  for m in net/can/can net/can/can-raw net/can/can-bcm drivers/net/can/dev/can-dev drivers/net/can/vcan; do
    insmod $M/$m.ko || { echo "init: cannot load $m"; exit 124; }
  done
  for i in vcan0 vcan1 vcan2 vcan3; do ip link add dev $i type vcan && ip link set $i up || { echo "init: cannot create $i"; exit 124; }; done
  ip link set lo up
  # Deep receive queues for every socket (candump, canbusload, the masters): a tool the
  # single-CPU guest does not schedule for a while must not drop frames.
  echo 8388608 > /proc/sys/net/core/rmem_max; echo 8388608 > /proc/sys/net/core/rmem_default
  cd "$CSP_CWD" && sh "$CSP_SCRIPT"
) > "$CSP_WORK/out" 2>&1
echo $? > "$CSP_WORK/rc"
sync
echo o > /proc/sysrq-trigger
sleep 10
INIT
chmod +x "$work/init"
script=$(cd "$(dirname "$script")" && pwd)/$(basename "$script")
timeout 900 "$uml" mem=512M uml_dir="$work" umid=csp-vcan root=/dev/root rootfstype=hostfs rootflags=/ rw \
  init="$work/init" CSP_WORK="$work" CSP_SCRIPT="$script" CSP_CWD="$PWD" "$@" \
  con=null con0=null,fd:2 quiet </dev/null 2>"$work/console"
cat "$work/out" 2>/dev/null
if [ ! -f "$work/rc" ]; then
  echo "run_in_uml: the guest left no exit code (boot failure or PID 1 died); console:" >&2
  tail -40 "$work/console" >&2
  exit 125
fi
exit "$(cat "$work/rc")"
