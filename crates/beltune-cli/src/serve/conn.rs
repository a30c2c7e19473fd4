//! One connection of the tuning page's server, before and around hyper.
//!
//! - [`read_head`]: the request head is read here first (within
//!   [`super::HEADER_READ_TIMEOUT`], at most [`MAX_HEAD_BYTES`]) and parsed
//!   with `httparse`, so that a malformed request gets a JSON answer naming
//!   what is wrong rather than hyper's bare status: a garbage request line
//!   (400), more than [`MAX_HEADERS`] headers (431), a target longer than
//!   [`super::MAX_URI_BYTES`] (414), a head larger than [`MAX_HEAD_BYTES`]
//!   (431), two `Content-Length` headers or `Content-Length` with
//!   `Transfer-Encoding` (400: request smuggling), no head in time (408).
//!   hyper then reads the same bytes again from [`Replay`].
//! - [`Replay`] also bounds writing: a client that stops reading its answers
//!   (a slow reader, or one that pipelines requests and never reads) has its
//!   connection closed after [`WRITE_TIMEOUT`] without progress, so it cannot
//!   hold one of the server's connection slots.
//! - One request per connection (no keep-alive, see [`super::serve`]): a slot
//!   is free again as soon as its answer is written.

use super::api::ErrorBody;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, ReadBuf};
use tokio::net::TcpStream;

/// Most headers a request may have.
pub const MAX_HEADERS: usize = 64;
/// Largest request head read before hyper, bytes (request line, headers and
/// the blank line).
pub const MAX_HEAD_BYTES: usize = 16 * 1024;
/// Longest a write to the client may make no progress.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(10);

/// A refusal of a request head: the status and the message of its JSON body.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HeadRefusal {
    /// HTTP status.
    pub status: u16,
    /// What is wrong, one line.
    pub message: String,
}

fn refusal(status: u16, message: impl Into<String>) -> HeadRefusal {
    HeadRefusal {
        status,
        message: message.into(),
    }
}

/// Check one complete or partial head (`bytes` as read so far): `Ok(true)`
/// when it is complete and acceptable, `Ok(false)` when more bytes are needed.
pub fn check_head(bytes: &[u8]) -> Result<bool, HeadRefusal> {
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut headers);
    let status = match req.parse(bytes) {
        Ok(s) => s,
        Err(httparse::Error::TooManyHeaders) => {
            return Err(refusal(
                431,
                format!("more than {MAX_HEADERS} request headers"),
            ))
        }
        Err(e) => return Err(refusal(400, format!("malformed request: {e}"))),
    };
    // the target is known as soon as the request line is: refuse early
    if let Some(path) = req.path {
        if path.len() > super::MAX_URI_BYTES {
            return Err(refusal(
                414,
                format!(
                    "request target of {} bytes is longer than {}",
                    path.len(),
                    super::MAX_URI_BYTES
                ),
            ));
        }
    }
    if status.is_partial() {
        let line_done = bytes.windows(2).any(|w| w == b"\r\n") || bytes.contains(&b'\n');
        if bytes.len() >= MAX_HEAD_BYTES {
            return Err(if line_done {
                refusal(
                    431,
                    format!("request head larger than {MAX_HEAD_BYTES} bytes"),
                )
            } else {
                refusal(
                    414,
                    format!("request line longer than {MAX_HEAD_BYTES} bytes"),
                )
            });
        }
        return Ok(false);
    }
    let count = |name: &str| {
        req.headers
            .iter()
            .filter(|h| h.name.eq_ignore_ascii_case(name))
            .count()
    };
    let lengths = count("content-length");
    if lengths > 1 {
        return Err(refusal(
            400,
            format!("{lengths} Content-Length headers; a request has at most one"),
        ));
    }
    if lengths == 1 && count("transfer-encoding") > 0 {
        return Err(refusal(
            400,
            "Content-Length together with Transfer-Encoding; send one of them",
        ));
    }
    Ok(true)
}

/// Read the request head from `stream` (and whatever followed it in the same
/// reads): the bytes for hyper, or the refusal to answer with.
pub async fn read_head(stream: &mut TcpStream) -> Result<Vec<u8>, HeadRefusal> {
    let mut bytes = Vec::with_capacity(1024);
    let read = async {
        let mut chunk = [0u8; 4096];
        loop {
            let room = (MAX_HEAD_BYTES - bytes.len()).min(chunk.len());
            let n = stream
                .read(&mut chunk[..room])
                .await
                .map_err(|e| refusal(400, format!("reading the request: {e}")))?;
            if n == 0 {
                return Err(refusal(400, "connection closed before a complete request"));
            }
            bytes.extend_from_slice(&chunk[..n]);
            if check_head(&bytes)? {
                return Ok(());
            }
        }
    };
    match tokio::time::timeout(super::HEADER_READ_TIMEOUT, read).await {
        Ok(Ok(())) => Ok(bytes),
        Ok(Err(e)) => Err(e),
        Err(_) => Err(refusal(
            408,
            format!(
                "request head not received within {} s",
                super::HEADER_READ_TIMEOUT.as_secs()
            ),
        )),
    }
}

/// Answer `status` with a JSON `{"error": ...}` body and close, within
/// [`WRITE_TIMEOUT`].
pub async fn answer_and_close(mut stream: TcpStream, status: u16, message: String) {
    let reason = axum::http::StatusCode::from_u16(status)
        .ok()
        .and_then(|s| s.canonical_reason())
        .unwrap_or("Error");
    let body = serde_json::to_string(&ErrorBody { error: message }).unwrap_or_default();
    let extra = if status == 503 {
        "retry-after: 1\r\n"
    } else {
        ""
    };
    let answer = format!(
        "HTTP/1.1 {status} {reason}\r\ncontent-type: application/json\r\n\
         content-length: {}\r\n{extra}x-frame-options: DENY\r\nconnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = tokio::time::timeout(WRITE_TIMEOUT, async {
        let _ = stream.write_all(answer.as_bytes()).await;
        let _ = stream.shutdown().await;
    })
    .await;
}

/// The connection as hyper sees it: the head already read is read again
/// first; a write that makes no progress for [`WRITE_TIMEOUT`] fails.
pub struct Replay<S = TcpStream> {
    head: Vec<u8>,
    at: usize,
    stream: S,
    stalled: Option<Pin<Box<tokio::time::Sleep>>>,
}

impl<S> Replay<S> {
    /// `head`: the bytes [`read_head`] took from `stream`.
    pub fn new(head: Vec<u8>, stream: S) -> Self {
        Replay {
            head,
            at: 0,
            stream,
            stalled: None,
        }
    }

    /// A pending write: start (or check) the stall timer.
    fn stall(&mut self, cx: &mut Context<'_>) -> Poll<io::Error> {
        let timer = self
            .stalled
            .get_or_insert_with(|| Box::pin(tokio::time::sleep(WRITE_TIMEOUT)));
        match timer.as_mut().poll(cx) {
            Poll::Ready(()) => Poll::Ready(io::Error::new(
                io::ErrorKind::TimedOut,
                "the client read nothing of its answer",
            )),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl<S: AsyncRead + Unpin> AsyncRead for Replay<S> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = &mut *self;
        if this.at < this.head.len() {
            let n = (this.head.len() - this.at).min(buf.remaining());
            buf.put_slice(&this.head[this.at..this.at + n]);
            this.at += n;
            return Poll::Ready(Ok(()));
        }
        Pin::new(&mut this.stream).poll_read(cx, buf)
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for Replay<S> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = &mut *self;
        match Pin::new(&mut this.stream).poll_write(cx, buf) {
            Poll::Ready(r) => {
                this.stalled = None;
                Poll::Ready(r)
            }
            Poll::Pending => this.stall(cx).map(Err),
        }
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = &mut *self;
        match Pin::new(&mut this.stream).poll_flush(cx) {
            Poll::Ready(r) => {
                this.stalled = None;
                Poll::Ready(r)
            }
            Poll::Pending => this.stall(cx).map(Err),
        }
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = &mut *self;
        match Pin::new(&mut this.stream).poll_shutdown(cx) {
            Poll::Ready(r) => Poll::Ready(r),
            Poll::Pending => this.stall(cx).map(Err),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_client_that_reads_nothing_is_cut_off_after_the_write_timeout() {
        let (server, mut client) = tokio::io::duplex(64);
        client.write_all(b"GET / HTTP/1.1\r\n\r\n").await.unwrap();
        let mut conn = Replay::new(b"HEAD".to_vec(), server);
        // the head is read again first, then the stream
        let mut first = [0u8; 4];
        conn.read_exact(&mut first).await.unwrap();
        assert_eq!(&first, b"HEAD");
        // an answer larger than what the client's side buffers, never read
        let t0 = tokio::time::Instant::now();
        let err = conn.write_all(&[b'x'; 4096]).await.unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::TimedOut);
        let waited = t0.elapsed();
        assert!(
            waited >= WRITE_TIMEOUT && waited < WRITE_TIMEOUT + Duration::from_secs(1),
            "{waited:?}"
        );
        // a client that reads keeps its connection: progress resets the timer
        let (server, mut client) = tokio::io::duplex(64);
        let mut conn = Replay::new(Vec::new(), server);
        let reader = tokio::spawn(async move {
            let mut sink = Vec::new();
            loop {
                tokio::time::sleep(WRITE_TIMEOUT / 4).await;
                let mut buf = [0u8; 64];
                match client.read(&mut buf).await {
                    Ok(0) | Err(_) => break,
                    Ok(n) => sink.extend_from_slice(&buf[..n]),
                }
            }
            sink.len()
        });
        conn.write_all(&[b'y'; 640]).await.unwrap();
        conn.shutdown().await.unwrap();
        drop(conn);
        assert_eq!(reader.await.unwrap(), 640);
    }

    #[test]
    fn a_complete_plain_head_passes_and_a_partial_one_waits() {
        let head = b"GET /api/info HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
        assert_eq!(check_head(head), Ok(true));
        assert_eq!(check_head(&head[..20]), Ok(false));
        assert_eq!(check_head(b""), Ok(false));
    }

    #[test]
    fn malformed_heads_are_refused_with_their_status() {
        let status = |h: &[u8]| check_head(h).unwrap_err().status;
        assert_eq!(status(b"\x16\x03\x01garbage\r\n\r\n"), 400);
        let many: String = (0..MAX_HEADERS + 1)
            .map(|k| format!("X-{k}: v\r\n"))
            .collect();
        assert_eq!(
            status(format!("GET / HTTP/1.1\r\n{many}\r\n").as_bytes()),
            431
        );
        let long = "a".repeat(super::super::MAX_URI_BYTES + 1);
        assert_eq!(status(format!("GET /{long} HTTP/1.1\r\n").as_bytes()), 414);
        let endless = "a".repeat(MAX_HEAD_BYTES);
        assert_eq!(status(format!("GET /{endless}").as_bytes()), 414);
        let big = format!("GET / HTTP/1.1\r\nX: {}", "b".repeat(MAX_HEAD_BYTES));
        assert_eq!(status(big.as_bytes()), 431);
        assert_eq!(
            status(b"POST / HTTP/1.1\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n"),
            400
        );
        assert_eq!(
            status(b"POST / HTTP/1.1\r\nContent-Length: 1\r\nTransfer-Encoding: chunked\r\n\r\n"),
            400
        );
    }
}
