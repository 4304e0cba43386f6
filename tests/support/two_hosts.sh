# Two hosts for multi-host tests, sourced by their scripts: network namespaces $a and $b joined by a
# veth pair ($if_a, $if_b) with TEST-NET-2 addresses (198.51.100.1 and .2, nothing routed anywhere
# else), a scratch folder $work, and $work/$if_a.xml, $work/$if_b.xml: the Cyclone config template
# filled in for each host. Everything goes on EXIT, with the PIDs the caller adds to $pids.
# Set before sourcing: template (config template), prefix (one letter that keeps parallel tests apart).
# Exits 77 (skipped) without root or ip netns.
[ "$(id -u)" -eq 0 ] || { echo "skip: needs root for ip netns"; exit 77; }
command -v ip >/dev/null || { echo "skip: needs iproute2"; exit 77; }

a="tachi-$prefix-a-$$" b="tachi-$prefix-b-$$" if_a="${prefix}a$$" if_b="${prefix}b$$"
work=$(mktemp -d /tmp/tachi-two-hosts-XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  ip netns del "$a" 2>/dev/null; ip netns del "$b" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
ip netns add "$a" && ip netns add "$b" || { echo "skip: cannot create network namespaces"; exit 77; }
ip link add "$if_a" netns "$a" type veth peer name "$if_b" netns "$b" || { echo "skip: cannot create veth"; exit 77; }
ip -n "$a" addr add 198.51.100.1/24 dev "$if_a"; ip -n "$b" addr add 198.51.100.2/24 dev "$if_b"
for ns in "$a" "$b"; do ip -n "$ns" link set lo up; done
ip -n "$a" link set "$if_a" up; ip -n "$b" link set "$if_b" up
for interface in "$if_a" "$if_b"; do
  sed -e "s/INTERFACE/$interface/" -e "s/HOST_A_ADDRESS/198.51.100.1/" -e "s/HOST_B_ADDRESS/198.51.100.2/" "$template" \
    > "$work/$interface.xml"
done
