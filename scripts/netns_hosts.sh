#!/usr/bin/env bash
# Two "hosts" on one machine for `pa10-dnbs launch --netns GROUP=NAMESPACE`: two Linux network namespaces
# joined by a veth link (docs/graph.md, "Several hosts on one machine"). Needs root and iproute2.
#
#   bash scripts/netns_hosts.sh up   [NS_A NS_B [PREFIX]]   create them: NS_A has PREFIX.1/24, NS_B PREFIX.2/24
#   bash scripts/netns_hosts.sh down [NS_A NS_B]            delete them (the veth link goes with them)
#   bash scripts/netns_hosts.sh status [NS_A NS_B]          their addresses and the link's packet counters
#
# Defaults: pa10_host_a pa10_host_b 10.77.0. In each namespace the link is `veth0` and loopback is up.
# `up` refuses a namespace that exists already (exit 1, nothing changed); `down` ignores missing ones.
set -euo pipefail
action="${1:-}"
A="${2:-pa10_host_a}"
B="${3:-pa10_host_b}"
PREFIX="${4:-10.77.0}"

die() { echo "netns_hosts: $1" >&2; exit "${2:-1}"; }
command -v ip >/dev/null 2>&1 || die "iproute2 (ip) is not installed"
[ "$A" != "$B" ] || die "the two namespaces must differ, got $A twice" 2
[[ "$PREFIX" =~ ^[0-9]+\.[0-9]+\.[0-9]+$ ]] || die "PREFIX must be three octets such as 10.77.0, got $PREFIX" 2

exists() { [ -e "/var/run/netns/$1" ]; }

case "$action" in
  up)
    [ "$(id -u)" -eq 0 ] || die "needs root (ip netns add)"
    for ns in "$A" "$B"; do
      if exists "$ns"; then die "network namespace $ns exists already (bash $0 down $A $B first)"; fi
    done
    tmp_a="p10a$$"; tmp_b="p10b$$"   # unique names in the root namespace (at most 15 characters)
    trap 'ip netns del "$A" 2>/dev/null || true; ip netns del "$B" 2>/dev/null || true; ip link del "$tmp_a" 2>/dev/null || true' ERR
    ip netns add "$A"
    ip netns add "$B"
    ip link add "$tmp_a" type veth peer name "$tmp_b"
    ip link set "$tmp_a" netns "$A"
    ip link set "$tmp_b" netns "$B"
    ip -n "$A" link set "$tmp_a" name veth0
    ip -n "$B" link set "$tmp_b" name veth0
    ip -n "$A" addr add "$PREFIX.1/24" dev veth0
    ip -n "$B" addr add "$PREFIX.2/24" dev veth0
    for ns in "$A" "$B"; do
      ip -n "$ns" link set veth0 up
      ip -n "$ns" link set lo up
    done
    echo "netns_hosts: $A ($PREFIX.1) <-> $B ($PREFIX.2) over veth0; run \`bash $0 down $A $B\` to remove them"
    ;;
  down)
    [ "$(id -u)" -eq 0 ] || die "needs root (ip netns del)"
    for ns in "$A" "$B"; do
      if exists "$ns"; then ip netns del "$ns"; fi
    done
    echo "netns_hosts: removed $A and $B"
    ;;
  status)
    for ns in "$A" "$B"; do
      exists "$ns" || die "no network namespace $ns"
      echo "== $ns"
      ip -n "$ns" -brief addr show dev veth0
      ip -n "$ns" -s link show dev veth0 | sed -n '3,6p'
    done
    ;;
  *)
    die "usage: bash $0 up|down|status [NS_A NS_B [PREFIX]]" 2
    ;;
esac
