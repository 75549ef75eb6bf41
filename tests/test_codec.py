"""The wire codec: round trips, and rejection of every malformed field with a message naming it."""

from __future__ import annotations

import json
import struct
from typing import Any

import numpy as np
import pytest

from worlds.bus.codec import ALLOWED_DTYPES, MAGIC, Limits, Message, WireError, decode, encode


def raw_message(header: Any, payload: bytes = b"", *, magic: bytes = MAGIC, header_len: int | None = None) -> bytes:
    """A message built by hand: ``header`` is JSON-encoded unless it is already bytes."""
    body = header if isinstance(header, bytes) else json.dumps(header).encode()
    length = len(body) if header_len is None else header_len
    return struct.pack(">4sI", magic, length) + body + payload


def one_array(dtype: str = "uint8", shape: Any = (2, 3), name: str = "x") -> dict[str, Any]:
    return {"arrays": [{"name": name, "dtype": dtype, "shape": list(shape) if isinstance(shape, tuple) else shape}]}


def assert_same(message: Message, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    assert message.meta == meta
    assert list(message.arrays) == list(arrays)
    for name, array in arrays.items():
        got = message.arrays[name]
        assert got.dtype == array.dtype, name
        assert got.shape == array.shape, name
        np.testing.assert_array_equal(got, array)


# --- round trips -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "array",
    [
        np.arange(24, dtype=np.uint8).reshape(2, 3, 4),
        np.arange(-6, 6, dtype=np.int16).reshape(3, 4),
        np.array([1, -2, 2**31 - 1, -(2**31)], dtype=np.int32),
        np.array([2**62, -(2**62)], dtype=np.int64),
        np.array([0, 1, 65535], dtype=np.uint16),
        np.linspace(-1, 1, 12, dtype=np.float32).reshape(2, 2, 3),
        np.array([[np.pi, -np.e], [np.inf, -0.0]], dtype=np.float64),
        np.array([[True, False], [False, True]]),
        np.zeros((0,), dtype=np.float32),
        np.zeros((4, 0, 2), dtype=np.int32),
        np.array(3.5, dtype=np.float64),  # zero-dimensional
    ],
    ids=lambda a: f"{a.dtype}{list(a.shape)}",
)
def test_round_trip_keeps_dtype_shape_and_values(array: np.ndarray) -> None:
    """Each allowed dtype and shape (empty and 0-d included) comes back identical."""
    meta = {"kind": "test", "n": 3, "nested": {"list": [1, 2.5, "x"], "none": None}}
    assert_same(decode(encode(meta, {"a": array})), meta, {"a": array})


def test_round_trip_meta_only() -> None:
    """A message without arrays carries its metadata and an empty array table."""
    for arrays in (None, {}):
        message = decode(encode({"ok": True, "error": "é ✓"}, arrays))
        assert message.meta == {"ok": True, "error": "é ✓"}
        assert message.arrays == {}
    assert decode(encode({})).meta == {}


def test_round_trip_several_arrays_in_order() -> None:
    """Several arrays keep their names, order and bytes; non-contiguous inputs are packed."""
    base = np.arange(30, dtype=np.float64).reshape(5, 6)
    arrays = {
        "rgb": np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3),
        "strided": base[::2, 1::2],  # not C-contiguous
        "transposed": base.T,  # Fortran order
        "mask": np.array([True, False, True]),
    }
    message = decode(encode({"k": 1}, arrays))
    assert_same(message, {"k": 1}, arrays)
    assert all(a.flags.c_contiguous and a.flags.writeable for a in message.arrays.values())


def test_big_endian_input_decodes_to_native_values() -> None:
    """A big-endian array is sent little-endian and read back as native values."""
    big = np.array([1.5, -2.25, 1e10], dtype=">f8")
    got = decode(encode({}, {"v": big})).arrays["v"]
    assert got.dtype == np.float64 and got.dtype.isnative
    np.testing.assert_array_equal(got, big.astype(np.float64))


def test_decode_accepts_bytearray_and_memoryview() -> None:
    data = encode({"a": 1}, {"x": np.arange(5, dtype=np.int64)})
    for wrapped in (bytearray(data), memoryview(data)):
        np.testing.assert_array_equal(decode(wrapped).arrays["x"], np.arange(5))


def test_randomized_round_trip() -> None:
    """Random dtypes, shapes, values and metadata from a seeded generator all round trip."""
    rng = np.random.default_rng(1234)
    names = sorted(ALLOWED_DTYPES)
    for trial in range(200):
        arrays: dict[str, np.ndarray] = {}
        for index in range(int(rng.integers(0, 5))):
            dtype = np.dtype(names[int(rng.integers(len(names)))])
            shape = tuple(int(n) for n in rng.integers(0, 5, size=int(rng.integers(0, 5))))
            if dtype == np.bool_:
                values = rng.random(shape) < 0.5
            elif dtype.kind == "f":
                values = rng.normal(0, 1e3, shape).astype(dtype)
            else:
                info = np.iinfo(dtype)
                values = rng.integers(info.min, info.max, shape, dtype=dtype, endpoint=True)
            arrays[f"a{index}"] = np.asarray(values, dtype=dtype)
        meta = {f"m{i}": float(rng.normal()) for i in range(int(rng.integers(0, 4)))}
        meta["trial"] = trial
        assert_same(decode(encode(meta, arrays)), meta, arrays)


# --- encode refuses ----------------------------------------------------------------------------


def test_encode_refuses_reserved_arrays_key() -> None:
    with pytest.raises(WireError, match=r"meta.*'arrays'.*reserved"):
        encode({"arrays": []})


@pytest.mark.parametrize(
    "array",
    [np.zeros(3, dtype=np.complex64), np.array([object(), 1], dtype=object), np.zeros(2, dtype=np.float16),
     np.array(["ab"])],
    ids=["complex64", "object", "float16", "str"],
)
def test_encode_refuses_unsupported_dtypes(array: np.ndarray) -> None:
    with pytest.raises(WireError, match=rf"arrays\.bad\.dtype: '{array.dtype.name}' is not one of"):
        encode({}, {"good": np.zeros(2), "bad": array})


# --- decode rejects ----------------------------------------------------------------------------


def test_rejects_unknown_dtype_in_header() -> None:
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.dtype: 'complex128' is not one of"):
        decode(raw_message(one_array("complex128", (1,)), b"\0" * 16))


def test_rejects_non_string_dtype_in_header() -> None:
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.dtype"):
        decode(raw_message(one_array(5, (1,)), b"\0"))  # type: ignore[arg-type]


def test_rejects_wrong_dtype_for_the_bytes_that_follow() -> None:
    """A header that claims float64 over 6 uint8 bytes is a size mismatch, not a misread."""
    with pytest.raises(WireError, match=r"arrays: the table describes 48 bytes but 6 follow"):
        decode(raw_message(one_array("float64", (2, 3)), bytes(6)))


@pytest.mark.parametrize("extra", [-1, 1, 100])
def test_rejects_payload_longer_or_shorter_than_table(extra: int) -> None:
    good = encode({}, {"x": np.arange(6, dtype=np.uint8).reshape(2, 3)})
    bad = good[:extra] if extra < 0 else good + bytes(extra)
    with pytest.raises(WireError, match=r"^arrays: the table describes 6 bytes but \d+ follow the header$"):
        decode(bad)


@pytest.mark.parametrize("length", [0, 1, 7])
def test_rejects_truncated_prefix(length: int) -> None:
    with pytest.raises(WireError, match=rf"message: truncated, {length} bytes is shorter than the 8-byte prefix"):
        decode(encode({"a": 1})[:length])


def test_rejects_truncated_header() -> None:
    data = encode({"some": "metadata"})
    with pytest.raises(WireError, match=r"header: truncated, \d+ of \d+ bytes present"):
        decode(data[:-3])


def test_rejects_oversize_header_before_reading_it() -> None:
    limits = Limits(max_header_bytes=32)
    data = encode({"text": "x" * 100})
    with pytest.raises(WireError, match=r"header: \d+ bytes exceeds the limit of 32"):
        decode(data, limits)
    # the length field alone decides: a huge declared length is refused without its bytes
    with pytest.raises(WireError, match=r"header: 4294967295 bytes exceeds the limit"):
        decode(raw_message({}, header_len=2**32 - 1))
    assert decode(encode({"t": "x"}), limits).meta == {"t": "x"}


def test_rejects_oversize_payload() -> None:
    limits = Limits(max_payload_bytes=100)
    fits = encode({}, {"a": np.zeros(100, np.uint8)})
    assert decode(fits, limits).arrays["a"].shape == (100,)
    one_too_many = encode({}, {"a": np.zeros(101, np.uint8)})
    with pytest.raises(WireError, match=r"header\.arrays\[0\]: 101 bytes exceeds the limit of 100"):
        decode(one_too_many, limits)
    # each array fits, the total does not
    together = encode({}, {"a": np.zeros(60, np.uint8), "b": np.zeros(60, np.uint8)})
    with pytest.raises(WireError, match=r"^arrays: 120 bytes exceeds the limit of 100"):
        decode(together, limits)


def test_rejects_huge_declared_array_without_its_bytes() -> None:
    """A table claiming terabytes is refused from the header alone."""
    with pytest.raises(WireError, match=r"header\.arrays\[0\]: \d+ bytes exceeds the limit"):
        decode(raw_message(one_array("float64", (2**20, 2**20))))


@pytest.mark.parametrize("shape", [[0, 2**70], [0, 2**62, 2**62], [2**40, 2**40, 0]])
def test_rejects_absurd_dims_of_an_empty_array(shape: list[int]) -> None:
    """A zero-size array with dimensions numpy cannot represent is a WireError, not a numpy error."""
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.shape"):
        decode(raw_message(one_array("uint8", shape)))


def test_rejects_too_many_arrays() -> None:
    limits = Limits(max_arrays=2)
    data = encode({}, {n: np.zeros(1, np.uint8) for n in "abc"})
    with pytest.raises(WireError, match=r"header\.arrays: 3 arrays exceeds the limit of 2"):
        decode(data, limits)


@pytest.mark.parametrize("magic", [b"HBW2", b"\0\0\0\0", b"GIF8"])
def test_rejects_bad_magic(magic: bytes) -> None:
    data = magic + encode({"a": 1})[4:]
    with pytest.raises(WireError, match=r"message: bad magic"):
        decode(data)


@pytest.mark.parametrize("body", [b"{not json", b"\xff\xfe{}", b"", b"{\"a\": 1,}"])
def test_rejects_non_json_header(body: bytes) -> None:
    with pytest.raises(WireError, match=r"header: not valid UTF-8 JSON"):
        decode(raw_message(body))


@pytest.mark.parametrize("header", [[1, 2], "text", 3, None, True])
def test_rejects_non_object_header(header: Any) -> None:
    with pytest.raises(WireError, match=r"header: must be a JSON object, got"):
        decode(raw_message(header))


@pytest.mark.parametrize("table", [{"name": "x"}, "x", 3])
def test_rejects_array_table_that_is_not_a_list(table: Any) -> None:
    with pytest.raises(WireError, match=r"header\.arrays: must be a list"):
        decode(raw_message({"arrays": table}))


@pytest.mark.parametrize(
    "entry",
    [
        {"name": "x", "dtype": "uint8"},
        {"name": "x", "dtype": "uint8", "shape": [1], "offset": 0},
        ["x", "uint8", [1]],
    ],
    ids=["missing-shape", "extra-field", "list-entry"],
)
def test_rejects_malformed_table_entry(entry: Any) -> None:
    with pytest.raises(WireError, match=r"header\.arrays\[0\]: must be an object with exactly name, dtype and shape"):
        decode(raw_message({"arrays": [entry]}, b"\0"))


def test_rejects_duplicate_array_names() -> None:
    header = {"arrays": [{"name": "x", "dtype": "uint8", "shape": [1]}, {"name": "x", "dtype": "uint8", "shape": [1]}]}
    with pytest.raises(WireError, match=r"header\.arrays\[1\]\.name: must be a unique non-empty string"):
        decode(raw_message(header, b"\0\0"))


@pytest.mark.parametrize("name", ["", 3, None])
def test_rejects_empty_or_non_string_name(name: Any) -> None:
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.name"):
        decode(raw_message(one_array(name=name, shape=(1,)), b"\0"))


@pytest.mark.parametrize(
    "shape",
    [[-1], [2, -3], [1.0], [2.5], ["3"], [None], [True], [1, False], 4, "2,3", [1, 1, 1, 1, 1]],
    ids=["neg", "neg2", "float-int", "float", "str", "none", "true", "false", "scalar", "string", "five-dims"],
)
def test_rejects_bad_dims(shape: Any) -> None:
    """Negative, non-integer and bool dims, a non-list shape and too many dims are all refused."""
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.shape: must be a list of at most 4 non-negative integers"):
        decode(raw_message(one_array("uint8", shape), b"\0"))


def test_max_ndim_comes_from_limits() -> None:
    data = encode({}, {"x": np.zeros((1, 1, 1), np.uint8)})
    assert decode(data).arrays["x"].shape == (1, 1, 1)
    with pytest.raises(WireError, match=r"header\.arrays\[0\]\.shape: must be a list of at most 2"):
        decode(data, Limits(max_ndim=2))


def test_decoded_arrays_do_not_alias_the_buffer() -> None:
    """Decoded arrays own their memory: changing the buffer afterwards does not change them."""
    buffer = bytearray(encode({}, {"x": np.arange(4, dtype=np.uint8)}))
    array = decode(buffer).arrays["x"]
    buffer[-4:] = b"\xff\xff\xff\xff"
    np.testing.assert_array_equal(array, np.arange(4))


# --- bounds a hostile sender cannot push past --------------------------------------------------


@pytest.mark.parametrize("depth", [65, 1_000, 30_000])
@pytest.mark.parametrize("opener, closer", [(b"[", b"]"), (b'{"a":', b"}")], ids=["lists", "objects"])
def test_rejects_nesting_deeper_than_64_levels(depth: int, opener: bytes, closer: bytes) -> None:
    with pytest.raises(WireError, match=r"^header: nested deeper than 64 levels"):
        decode(raw_message(b'{"x":' + opener * (depth - 1) + b"1" + closer * (depth - 1) + b"}"))


def test_accepts_nesting_of_64_levels_and_brackets_inside_strings() -> None:
    deep = b'{"x":' + b"[" * 63 + b"1" + b"]" * 63 + b"}"
    value = decode(raw_message(deep)).meta["x"]
    for _ in range(63):
        (value,) = value
    assert value == 1
    text = "[" * 500 + '\\"' + "{" * 500
    assert decode(raw_message({"text": text})).meta == {"text": text}


@pytest.mark.parametrize("digits", [21, 400, 4_301, 5_000, 100_000])
@pytest.mark.parametrize("sign", ["", "-"])
def test_rejects_integers_beyond_64_bits_naming_their_field(digits: int, sign: str) -> None:
    header = b'{"path": [[1.0, ' + sign.encode() + b"9" * digits + b"]], \"arrays\": []}"
    with pytest.raises(WireError, match=rf"^header\.path\[0\]\[1\]: the integer .*\({digits} digits\) is outside the "
                                        r"64-bit range") as caught:
        decode(raw_message(header))
    assert (caught.value.field, caught.value.problem.split(" ")[0]) == ("path[0][1]", "the")


def test_keeps_the_whole_64_bit_range() -> None:
    meta = {"low": -(2**63), "high": 2**64 - 1, "seed": 2**63 - 1}
    assert decode(encode(meta)).meta == meta
    with pytest.raises(WireError, match=r"^header\.high: the integer 18446744073709551616 \(20 digits\)"):
        decode(encode({"high": 2**64}))


def test_an_oversized_integer_in_the_array_table_is_the_table_s_fault() -> None:
    with pytest.raises(WireError, match=r"^header\.arrays\[0\]\.shape\[0\]: the integer") as caught:
        decode(raw_message(b'{"arrays": [{"name": "x", "dtype": "uint8", "shape": [' + b"9" * 30 + b"]}]}"))
    assert caught.value.field == ""  # not a metadata field: a server does not name it after its command


@pytest.mark.parametrize("byte", [2, 255])
def test_rejects_bool_bytes_other_than_0_and_1(byte: int) -> None:
    with pytest.raises(WireError, match=rf"^arrays\.flags: a bool element is one byte, 0 or 1; found {byte}"):
        decode(raw_message(one_array("bool", [3], "flags"), bytes([1, byte, 0])))
    assert decode(raw_message(one_array("bool", [3], "flags"), b"\x01\x00\x01")).arrays["flags"].tolist() == [
        True, False, True]
