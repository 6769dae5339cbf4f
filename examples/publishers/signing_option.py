"""The publishers' --key / --link-id: sign what they send when motormix requires it.

A configuration with `security.mode: require` (config/quad_x_field.yaml) refuses
every unsigned message and counts it on the status's `signed` line. Give the
publisher the bus key (`motormix keygen`) and a link id of its own (0..255, one
per sender) and each message carries the signature motormix checks
(python/motormix_signing.py, installed beside the message types).
"""
import sys


def add_arguments(parser):
    parser.add_argument("--key", default="",
                        help="sign with this bus key file (for security.mode sign or require)")
    parser.add_argument("--link-id", type=int, default=3,
                        help="this publisher's link id when signing (0..255, one per sender)")


def publisher(args, bus):
    """A publish(channel, payload, utime) that signs when --key was given."""
    if not args.key:
        return lambda channel, payload, utime: bus.publish(channel, payload)
    import motormix_signing  # only when signing: the unsigned path needs nothing more
    try:
        key = motormix_signing.load_key(args.key)
    except motormix_signing.KeyError_ as e:
        sys.exit(f"--key: {e}")
    if not 0 <= args.link_id <= 255:
        sys.exit("--link-id: 0..255")
    signer = motormix_signing.Signer(key, args.link_id)
    return lambda channel, payload, utime: bus.publish(channel,
                                                       signer.sign(channel, payload, utime))
