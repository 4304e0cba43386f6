#!/usr/bin/env bash
# Runs DDS tests on a test host that also has a non-loopback interface, and fails if a single
# packet appears on that interface. The host is a network namespace this script makes itself
# (a veth pair into a second namespace, nothing routed further), so a config that fell back to
# Cyclone's defaults (multicast on every interface) is caught here and never reaches a real network.
# Usage: loopback_only_test.sh COMMAND [ARGS...]   (exit 77 = skipped: needs root, ip netns, tcpdump)
set -u
[ "$(id -u)" -eq 0 ] || { echo "skip: needs root for ip netns"; exit 77; }
command -v ip >/dev/null && command -v tcpdump >/dev/null || { echo "skip: needs iproute2 and tcpdump"; exit 77; }

host="tachi-lo-host-$$"
peer="tachi-lo-peer-$$"
cleanup() {
  [ -n "${capture_pid:-}" ] && kill "$capture_pid" 2>/dev/null
  ip netns del "$host" 2>/dev/null
  ip netns del "$peer" 2>/dev/null
  rm -f "$pcap"
}
pcap=$(mktemp /tmp/tachi-lo-XXXXXX.pcap)
trap cleanup EXIT
ip netns add "$host" && ip netns add "$peer" || { echo "skip: cannot create network namespaces"; exit 77; }
ip link add "veth-h$$" netns "$host" type veth peer name "veth-p$$" netns "$peer" || { echo "skip: cannot create veth"; exit 77; }
# 198.51.100.0/24 is TEST-NET-2 (RFC 5737): documentation-only addresses, used only between the two namespaces.
ip -n "$host" addr add 198.51.100.1/24 dev "veth-h$$"
ip -n "$peer" addr add 198.51.100.2/24 dev "veth-p$$"
ip -n "$host" link set lo up
ip -n "$host" link set "veth-h$$" up
ip -n "$peer" link set "veth-p$$" up
ip -n "$host" route add 224.0.0.0/4 dev "veth-h$$"  # give multicast a way out, so a leak would show

ip netns exec "$host" tcpdump -i "veth-h$$" -n -U -w "$pcap" 2>/dev/null &
capture_pid=$!
# tcpdump writes the pcap file header once it captures (-U: unbuffered); up to 5 s on a loaded machine.
for _ in $(seq 100); do [ -s "$pcap" ] && break; sleep 0.05; done
[ -s "$pcap" ] || { echo "FAIL: tcpdump did not start capturing on veth-h$$"; exit 1; }
ip netns exec "$host" "$@"
status=$?
sleep 1  # a packet sent as the command ended still reaches the capture
kill "$capture_pid" 2>/dev/null; wait "$capture_pid" 2>/dev/null; capture_pid=
packets=$(tcpdump -r "$pcap" -n 2>/dev/null | grep -vE 'ICMP6|IP6 fe80|ARP' )
count=$(printf '%s' "$packets" | grep -c . || true)
echo "command exit status $status; packets on the non-loopback interface: $count"
[ "$count" -eq 0 ] || { echo "$packets" | head -20; exit 1; }
exit "$status"
