// Command vectors_go checks mavconform's golden vectors with gomavlib, an independent MAVLink
// implementation in Go (github.com/bluenviron/gomavlib), using the dialect gomavlib itself
// ships: "development" (upstream common.xml plus development.xml, as gomavlib generated it from
// upstream's XML). Nothing here comes from mavconform's own XML or codec.
//
// stdin: one vector per line, "ID SIGNED HEX" (SIGNED is 0 or 1); argv[1]: the test key, hex.
// stdout: one JSON object per vector, the result format of vectors/verify.py:
//
//	{"id":..,"ok":true,"msgid":..,"sysid":..,"compid":..,"seq":..,"fields":{..},"signature":..,"reencoded":"hex"}
//	{"id":..,"ok":false,"error":"bad_crc|bad_length|unknown_msgid|bad_signature|unknown_incompat_flags|other","detail":".."}
//
// Decoding is gomavlib's frame.Reader (checksum, signature, truncation, extensions); re-encoding
// is gomavlib's message encoder, checksum and signature over the decoded message with the
// vector's header and signature block. Field names are gomavlib's (its `mavname` tag, or its
// Go name in snake case, as gomavlib maps them to the XML).
package main

import (
	"bufio"
	"bytes"
	"encoding/hex"
	"encoding/json"
	"errors"
	"fmt"
	"io"
	"math"
	"os"
	"reflect"
	"regexp"
	"sort"
	"strconv"
	"strings"

	"github.com/bluenviron/gomavlib/v3/pkg/dialect"
	"github.com/bluenviron/gomavlib/v3/pkg/dialects/development"
	"github.com/bluenviron/gomavlib/v3/pkg/frame"
	"github.com/bluenviron/gomavlib/v3/pkg/message"
)

var upper = regexp.MustCompile("([A-Z])")

func main() {
	if len(os.Args) == 2 && os.Args[1] == "--describe" {
		describe()
		return
	}
	if len(os.Args) != 2 {
		fmt.Fprintln(os.Stderr, "usage: vectors_go KEYHEX < vectors | vectors_go --describe")
		os.Exit(2)
	}
	keyBytes, err := hex.DecodeString(os.Args[1])
	if err != nil || len(keyBytes) != 32 {
		fmt.Fprintln(os.Stderr, "vectors_go: the key is 64 hex digits")
		os.Exit(2)
	}
	key := frame.NewV2Key(keyBytes)
	rw := &dialect.ReadWriter{Dialect: development.Dialect}
	if err := rw.Initialize(); err != nil {
		fmt.Fprintln(os.Stderr, "vectors_go: dialect:", err)
		os.Exit(1)
	}
	in := bufio.NewScanner(os.Stdin)
	in.Buffer(make([]byte, 1<<16), 1<<20)
	out := bufio.NewWriter(os.Stdout)
	defer out.Flush()
	for in.Scan() {
		parts := strings.Fields(in.Text())
		if len(parts) != 3 {
			continue
		}
		raw, err := hex.DecodeString(parts[2])
		if err != nil {
			fmt.Fprintln(os.Stderr, "vectors_go: bad hex for", parts[0])
			os.Exit(2)
		}
		res := check(rw, key, parts[1] == "1", raw)
		res["id"] = parts[0]
		out.WriteString(encode(res))
		out.WriteString("\n")
	}
}

// describe prints, by message id, what gomavlib's development dialect knows of each
// message: its name, its CRC_EXTRA as gomavlib computes it, and its fields (XML names, and
// whether each is an extension), so the caller can say precisely what it lacks.
func describe() {
	rw := &dialect.ReadWriter{Dialect: development.Dialect}
	if err := rw.Initialize(); err != nil {
		fmt.Fprintln(os.Stderr, "vectors_go: dialect:", err)
		os.Exit(1)
	}
	out := map[string]any{}
	for _, msg := range development.Dialect.Messages {
		t := reflect.TypeOf(msg).Elem()
		var list []any
		for i := 0; i < t.NumField(); i++ {
			f := t.Field(i)
			list = append(list, map[string]any{"name": fieldName(f), "extension": f.Tag.Get("mavext") == "true"})
		}
		name := strings.ToUpper(upper.ReplaceAllString(strings.TrimPrefix(t.Name(), "Message"), "_${1}")[1:])
		out[strconv.FormatUint(uint64(msg.GetID()), 10)] = map[string]any{
			"name": name, "crc_extra": rw.GetMessage(msg.GetID()).CRCExtra(), "fields": list}
	}
	fmt.Println(encode(out))
}

func fieldName(f reflect.StructField) string {
	if name := f.Tag.Get("mavname"); name != "" {
		return name
	}
	return strings.ToLower(upper.ReplaceAllString(f.Name, "_${1}")[1:])
}

func check(rw *dialect.ReadWriter, key *frame.V2Key, signed bool, raw []byte) map[string]any {
	r := &frame.Reader{BufByteReader: bufio.NewReader(bytes.NewReader(raw)), DialectRW: rw}
	if signed {
		r.InKey = key
	}
	if err := r.Initialize(); err != nil {
		return refused("other", err.Error())
	}
	fr, err := r.Read()
	if err != nil {
		return refused(classify(err), err.Error())
	}
	if extra, _ := io.ReadAll(r.BufByteReader); len(extra) > 0 {
		return refused("other", fmt.Sprintf("%d bytes after the frame", len(extra)))
	}
	msg := fr.GetMessage()
	if _, isRaw := msg.(*message.MessageRaw); isRaw {
		return refused("unknown_msgid", fmt.Sprintf("message id %d is not in gomavlib's development dialect", msg.GetID()))
	}
	mp := rw.GetMessage(msg.GetID())
	res := map[string]any{"ok": true, "msgid": msg.GetID(), "sysid": fr.GetSystemID(),
		"compid": fr.GetComponentID(), "seq": fr.GetSequenceNumber(), "fields": fields(msg), "signature": nil}
	var buf bytes.Buffer
	w := &frame.Writer{ByteWriter: &buf}
	if err := w.Initialize(); err != nil {
		return refused("other", err.Error())
	}
	switch f := fr.(type) {
	case *frame.V1Frame:
		nf := &frame.V1Frame{SequenceNumber: f.SequenceNumber, SystemID: f.SystemID, ComponentID: f.ComponentID,
			Message: mp.Write(msg, false)}
		nf.Checksum = nf.GenerateChecksum(mp.CRCExtra())
		err = w.Write(nf)
	case *frame.V2Frame:
		nf := &frame.V2Frame{IncompatibilityFlag: f.IncompatibilityFlag, CompatibilityFlag: f.CompatibilityFlag,
			SequenceNumber: f.SequenceNumber, SystemID: f.SystemID, ComponentID: f.ComponentID,
			Message: mp.Write(msg, true)}
		nf.Checksum = nf.GenerateChecksum(mp.CRCExtra())
		if f.IsSigned() {
			nf.SignatureLinkID, nf.SignatureTimestamp = f.SignatureLinkID, f.SignatureTimestamp
			nf.Signature = nf.GenerateSignature(key)
			res["signature"] = map[string]any{"link_id": f.SignatureLinkID, "timestamp": f.SignatureTimestamp}
		}
		err = w.Write(nf)
	}
	if err != nil {
		return refused("other", "re-encoding: "+err.Error())
	}
	res["reencoded"] = hex.EncodeToString(buf.Bytes())
	return res
}

// classify maps gomavlib's reader errors to the vectors' error vocabulary.
func classify(err error) string {
	text := err.Error()
	switch {
	case errors.Is(err, io.EOF), errors.Is(err, io.ErrUnexpectedEOF), strings.Contains(text, "EOF"):
		return "bad_length" // the bytes end before the frame its length byte announces
	case strings.Contains(text, "checksum"):
		return "bad_crc"
	case strings.Contains(text, "signature"):
		return "bad_signature"
	case strings.Contains(text, "incompatibility flag"):
		return "unknown_incompat_flags"
	case strings.Contains(text, "wrong size"):
		return "bad_length" // MAVLink 1 payload not the message's length
	}
	return "other"
}

func refused(kind, detail string) map[string]any {
	return map[string]any{"ok": false, "error": kind, "detail": detail}
}

func fields(msg message.Message) map[string]any {
	out := map[string]any{}
	v := reflect.ValueOf(msg).Elem()
	t := v.Type()
	for i := 0; i < t.NumField(); i++ {
		out[fieldName(t.Field(i))] = value(v.Field(i))
	}
	return out
}

// jsonFloat keeps a float's value exact in JSON: NaN and infinities as strings, and always
// a float literal, so -0 stays -0.0.
type jsonFloat string

func value(v reflect.Value) any {
	switch v.Kind() {
	case reflect.Array, reflect.Slice:
		list := make([]any, v.Len())
		for i := range list {
			list[i] = value(v.Index(i))
		}
		return list
	case reflect.String:
		return v.String()
	case reflect.Float32, reflect.Float64:
		bits := 64
		if v.Kind() == reflect.Float32 {
			bits = 32
		}
		f := v.Float()
		switch {
		case math.IsNaN(f):
			return "NaN"
		case math.IsInf(f, 1):
			return "Infinity"
		case math.IsInf(f, -1):
			return "-Infinity"
		}
		s := strconv.FormatFloat(f, 'g', -1, bits)
		if !strings.ContainsAny(s, ".e") {
			s += ".0"
		}
		return jsonFloat(s)
	case reflect.Int, reflect.Int8, reflect.Int16, reflect.Int32, reflect.Int64:
		return v.Int()
	default:
		return v.Uint()
	}
}

func encode(v any) string {
	switch x := v.(type) {
	case jsonFloat:
		return string(x)
	case map[string]any:
		keys := make([]string, 0, len(x))
		for k := range x {
			keys = append(keys, k)
		}
		sort.Strings(keys)
		parts := make([]string, len(keys))
		for i, k := range keys {
			parts[i] = encode(k) + ":" + encode(x[k])
		}
		return "{" + strings.Join(parts, ",") + "}"
	case []any:
		parts := make([]string, len(x))
		for i, e := range x {
			parts[i] = encode(e)
		}
		return "[" + strings.Join(parts, ",") + "]"
	default:
		b, err := json.Marshal(x)
		if err != nil {
			return "null"
		}
		return string(b)
	}
}
