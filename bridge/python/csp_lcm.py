"""A pure-Python LCM client for LCM's UDP multicast transport (udpm://), for hosts without LCM's
own Python module (Debian 12 packages LCM's C, C++ and Java libraries, not its Python one).

It speaks LCM's UDP multicast protocol (LCM's docs/content/udp-multicast-protocol.md), so it talks
to any LCM program: `csp serve`, lcm-logger, lcm-logplayer, lcm-spy. Its LCM class has the calls of
lcm.LCM that the types lcm-gen writes and CSP's Python tools use, with the same arguments:

    lc = csp_lcm.LCM("udpm://239.255.76.67:7667?ttl=0")
    subscription = lc.subscribe("CSP_STATE", handler)   # handler(channel, data); channel is a regex
    lc.publish("CSP_COMMAND", message.encode())
    lc.handle_timeout(100)                               # 1 if a message was handled, 0 on timeout
    lc.unsubscribe(subscription)

Prefer LCM's own module where it is installed (`import lcm`); this one is the stand-in with the
same API. Not provided: LCM's other transports (file://, memq://, tcpq://), EventLog, and
LCMSubscription.set_queue_capacity. Received datagrams wait in the kernel's socket buffer until
handle() reads them (LCM's library reads them in a thread of its own), and what does not fit is lost:
for messages of more than about 100 kB add recv_buf_size=BYTES to the URL (the kernel caps it at
net.core.rmem_max).
"""
import os
import re
import select
import socket
import struct
import time
import urllib.parse

DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"   # LCM's default when LCM_DEFAULT_URL is not set

# The protocol's limits and headers (all fields big-endian).
SHORT_MAGIC = 0x4C433032             # "LC02": a whole message in one datagram
FRAGMENT_MAGIC = 0x4C433033          # "LC03": one fragment of a larger message
SHORT_HEADER = struct.Struct(">II")  # magic, sequence number
FRAGMENT_HEADER = struct.Struct(">IIIIHH")   # magic, sequence number, payload size, offset, fragment number, fragments
MAX_DATAGRAM = 65507                 # the largest UDP payload over IPv4
MAX_CHANNEL_LENGTH = 63              # bytes, without the terminating NUL
MAX_MESSAGE_SIZE = 1 << 28           # LCM refuses larger payloads
MAX_PARTIAL_MESSAGES = 64            # senders with a fragmented message under way; the oldest is dropped beyond


def parse_url(url):
    """(group, port, ttl, receive buffer size or None) of a udpm:// URL; ValueError naming what is wrong."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme != "udpm":
        raise ValueError(f"LCM URL {url!r}: csp_lcm supports udpm:// only (LCM's own Python module has the others)")
    try:
        group, port = parts.hostname or "239.255.76.67", parts.port or 7667
        if not socket.inet_aton(group) or not 224 <= int(group.split(".")[0]) <= 239:
            raise ValueError
    except (OSError, ValueError):   # inet_aton's OSError: not an IPv4 address
        raise ValueError(f"LCM URL {url!r}: expected udpm://MULTICAST_IPV4:PORT") from None
    ttl, receive_buffer = 0, None
    for key, value in urllib.parse.parse_qsl(parts.query, keep_blank_values=True):
        if key not in ("ttl", "recv_buf_size") or not value.isdigit():
            raise ValueError(f"LCM URL {url!r}: unknown option or bad value {key}={value!r} (ttl=N, recv_buf_size=BYTES)")
        if key == "ttl":
            ttl = int(value)
        else:
            receive_buffer = int(value)
    if ttl > 255:
        raise ValueError(f"LCM URL {url!r}: ttl {ttl} is above 255")
    return group, port, ttl, receive_buffer


class LCMSubscription:
    """What subscribe() returns; pass it to unsubscribe()."""

    def __init__(self, channel, handler):
        self.channel = channel
        self.pattern = re.compile(channel)   # LCM matches the whole channel name against the regex
        self.handler = handler


class _PartialMessage:
    """The fragments of one message received so far, from one sender."""

    def __init__(self, sequence_number, size, fragments):
        self.sequence_number = sequence_number
        self.data = bytearray(size)
        self.missing = set(range(fragments))
        self.channel = None   # known once fragment 0 has arrived


class LCM:
    """An LCM client on one udpm:// multicast group and port (see the module's text)."""

    def __init__(self, provider=None):
        url = provider or os.environ.get("LCM_DEFAULT_URL") or DEFAULT_URL
        group, port, ttl, receive_buffer = parse_url(url)
        self._destination = (group, port)
        self._subscriptions = []
        self._partial = {}   # sender address -> _PartialMessage
        self._sequence_number = 0
        # One socket sends and receives. As LCM's own sockets: several programs on this host may bind
        # the same group and port, each gets every datagram, and our own messages loop back to us.
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        try:
            self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if receive_buffer:
                self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
            self._socket.bind((group, port))   # the group's address: datagrams to other groups on this port stay out
            membership = socket.inet_aton(group) + socket.inet_aton("0.0.0.0")
            self._socket.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
            self._socket.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, ttl)
            self._socket.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        except OSError as error:
            self._socket.close()
            raise OSError(f"LCM URL {url!r}: cannot join the multicast group: {error.strerror} "
                          "(is there a route for 224.0.0.0/4, e.g. on lo? see LCM's multicast-setup notes)") from None

    def fileno(self):
        """The socket, for select(): readable when a datagram waits (handle_timeout(0) then returns at once)."""
        return self._socket.fileno()

    def close(self):
        self._socket.close()

    def subscribe(self, channel, handler):
        """Calls handler(channel, data) for each message whose whole channel name matches the regex `channel`."""
        subscription = LCMSubscription(channel, handler)
        self._subscriptions.append(subscription)
        return subscription

    def unsubscribe(self, subscription):
        if subscription not in self._subscriptions:
            raise ValueError("unsubscribe: not a subscription of this LCM object")
        self._subscriptions.remove(subscription)

    def publish(self, channel, data):
        """Sends `data` (bytes) on `channel`: in one datagram, or in fragments when it does not fit in one."""
        name = channel.encode("utf-8") + b"\0"
        if len(name) - 1 > MAX_CHANNEL_LENGTH:
            raise ValueError(f"publish: channel name {channel!r} is longer than {MAX_CHANNEL_LENGTH} bytes")
        data = bytes(data)
        if len(data) > MAX_MESSAGE_SIZE:
            raise ValueError(f"publish: {len(data)} bytes, above LCM's limit of {MAX_MESSAGE_SIZE}")
        sequence_number = self._sequence_number
        self._sequence_number = (sequence_number + 1) & 0xFFFFFFFF
        if SHORT_HEADER.size + len(name) + len(data) <= MAX_DATAGRAM:
            self._socket.sendto(SHORT_HEADER.pack(SHORT_MAGIC, sequence_number) + name + data, self._destination)
            return
        # Fragments: the first carries the channel name, every one at most MAX_DATAGRAM bytes.
        room = MAX_DATAGRAM - FRAGMENT_HEADER.size
        bounds = [0, room - len(name)]
        while bounds[-1] < len(data):
            bounds.append(min(bounds[-1] + room, len(data)))
        fragments = len(bounds) - 1
        if fragments > 0xFFFF:
            raise ValueError(f"publish: {len(data)} bytes need more than 65535 fragments")
        for number in range(fragments):
            start, end = bounds[number], bounds[number + 1]
            header = FRAGMENT_HEADER.pack(FRAGMENT_MAGIC, sequence_number, len(data), start, number, fragments)
            self._socket.sendto(header + (name if number == 0 else b"") + data[start:end], self._destination)

    def handle(self):
        """Waits for the next message of a subscribed channel and calls its handlers."""
        while not self._receive_one(None):
            pass

    def handle_timeout(self, timeout_millis):
        """As handle(), waiting at most timeout_millis: 1 if a message was handled, 0 if the time ran out."""
        if timeout_millis < 0:
            raise ValueError("handle_timeout: the timeout must not be negative")
        deadline = time.monotonic() + timeout_millis * 1e-3
        while True:
            if self._receive_one(max(0.0, deadline - time.monotonic())):
                return 1
            if time.monotonic() >= deadline:
                return 0

    def _receive_one(self, timeout):
        """Reads at most one datagram (waiting up to `timeout` s, or forever if None); True if it
        completed a message that some subscription handled."""
        readable, _, _ = select.select([self._socket], [], [], timeout)
        if not readable:
            return False
        datagram, sender = self._socket.recvfrom(MAX_DATAGRAM)
        message = self._message_of(datagram, sender)
        if message is None:
            return False
        channel, data = message
        handlers = [s.handler for s in self._subscriptions if s.pattern.fullmatch(channel)]
        for handler in handlers:
            handler(channel, data)
        return bool(handlers)

    def _message_of(self, datagram, sender):
        """(channel, data) of the message this datagram completes, or None. Malformed datagrams are
        dropped as LCM drops them: a UDP bus carries whatever anyone sends."""
        if len(datagram) < SHORT_HEADER.size:
            return None
        magic, sequence_number = SHORT_HEADER.unpack_from(datagram)
        if magic == SHORT_MAGIC:
            channel, end = _channel_at(datagram, SHORT_HEADER.size)
            return None if channel is None else (channel, datagram[end:])
        if magic != FRAGMENT_MAGIC or len(datagram) < FRAGMENT_HEADER.size:
            return None
        _, _, size, offset, number, fragments = FRAGMENT_HEADER.unpack_from(datagram)
        if size > MAX_MESSAGE_SIZE or number >= fragments:
            return None
        partial = self._partial.get(sender)
        # A sender sends its fragments back to back: another message from it means this one lost some.
        if partial is None or partial.sequence_number != sequence_number or len(partial.data) != size:
            self._partial.pop(sender, None)
            if len(self._partial) >= MAX_PARTIAL_MESSAGES:
                del self._partial[next(iter(self._partial))]
            partial = self._partial[sender] = _PartialMessage(sequence_number, size, fragments)
        start = FRAGMENT_HEADER.size
        if number == 0:
            partial.channel, start = _channel_at(datagram, start)
            if partial.channel is None:
                del self._partial[sender]
                return None
        piece = datagram[start:]
        if offset + len(piece) > size:
            del self._partial[sender]
            return None
        partial.data[offset:offset + len(piece)] = piece
        partial.missing.discard(number)
        if partial.missing:
            return None
        del self._partial[sender]
        return partial.channel, bytes(partial.data)


def _channel_at(datagram, start):
    """(channel name, index after its NUL) at `start`, or (None, start) if it is not a valid name."""
    end = datagram.find(b"\0", start, start + MAX_CHANNEL_LENGTH + 1)
    if end < 0:
        return None, start
    try:
        return datagram[start:end].decode("utf-8"), end + 1
    except UnicodeDecodeError:
        return None, start
