// @ts-check
// Camera capture for the photos step: a dialog with the live camera (getUserMedia), a shutter
// that may be pressed several times (several views of the object), a front/back switch when the
// device has more than one camera, and messages a person can act on when the camera is denied
// or missing. Shots come out as JPEG blobs and go through the same loader as any photo.
import { el } from './ui.js';

/** Why getUserMedia failed, said so a person knows what to do next. */
export function cameraErrorMessage(err) {
  const name = err && err.name;
  if (!window.isSecureContext) return 'The camera needs a secure page (https or localhost). Choose a photo file instead.';
  if (name === 'NotAllowedError' || name === 'SecurityError') {
    return 'Camera access was denied. Allow the camera for this site in the browser’s settings, or choose a photo file instead.';
  }
  if (name === 'NotFoundError' || name === 'OverconstrainedError') return 'No camera was found on this device. Choose a photo file instead.';
  if (name === 'NotReadableError') return 'The camera is busy in another app. Close it there and try again.';
  return `The camera could not start (${(err && err.message) || name || 'unknown error'}). Choose a photo file instead.`;
}

export class CameraCapture {
  /** `onShot(blob)` receives each photo taken; `onError(message)` a failure to show. */
  constructor({ onShot, onError }) {
    this.onShot = onShot;
    this.onError = onError;
    this.facing = 'environment';
    this.stream = null;
    this.shots = 0;
    this.video = el('video', { playsinline: true, muted: true, autoplay: true, 'aria-label': 'Camera preview' });
    this.count = el('p', { class: 'muted', role: 'status', 'aria-live': 'polite' }, ['No shots yet']);
    this.shutter = el('button', { type: 'button', class: 'primary', id: 'camera-shoot' }, ['Take photo']);
    this.switcher = el('button', { type: 'button', id: 'camera-switch', hidden: true }, ['Switch camera']);
    this.done = el('button', { type: 'button', id: 'camera-done' }, ['Done']);
    this.dialog = el('dialog', { id: 'camera', 'aria-labelledby': 'camera-title' }, [
      el('h2', { id: 'camera-title' }, ['Take photos']),
      el('p', { class: 'muted' }, ['Walk around the object and take one or more shots; keep all of it in view.']),
      this.video,
      this.count,
      el('div', { class: 'row' }, [this.shutter, this.switcher, this.done]),
    ]);
    document.body.append(this.dialog);
    this.shutter.addEventListener('click', () => this.shoot());
    this.switcher.addEventListener('click', () => this.switchCamera());
    this.done.addEventListener('click', () => this.close());
    this.dialog.addEventListener('close', () => this.stop());
  }

  async open() {
    if (!navigator.mediaDevices?.getUserMedia) {
      this.onError(cameraErrorMessage(null));
      return;
    }
    this.shots = 0;
    this.count.textContent = 'No shots yet';
    try {
      await this.start();
    } catch (err) {
      this.onError(cameraErrorMessage(err));
      return;
    }
    this.dialog.showModal();
    this.shutter.focus();
    try {
      const cams = (await navigator.mediaDevices.enumerateDevices()).filter((d) => d.kind === 'videoinput');
      this.switcher.hidden = cams.length < 2;
    } catch {
      this.switcher.hidden = true;
    }
  }

  async start() {
    this.stop();
    this.stream = await navigator.mediaDevices.getUserMedia({
      video: { facingMode: { ideal: this.facing }, width: { ideal: 1920 }, height: { ideal: 1080 } },
      audio: false,
    });
    this.video.srcObject = this.stream;
    await this.video.play().catch(() => {});
  }

  async switchCamera() {
    this.facing = this.facing === 'environment' ? 'user' : 'environment';
    try {
      await this.start();
    } catch (err) {
      this.onError(cameraErrorMessage(err));
    }
  }

  async shoot() {
    const v = this.video;
    if (!v.videoWidth) return;
    const canvas = new OffscreenCanvas(v.videoWidth, v.videoHeight);
    canvas.getContext('2d').drawImage(v, 0, 0);
    const blob = await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 });
    this.shots += 1;
    this.count.textContent = `${this.shots} shot${this.shots === 1 ? '' : 's'} taken`;
    this.onShot(blob, `camera ${this.shots}.jpg`);
  }

  stop() {
    const tracks = this.stream?.getTracks() ?? [];
    tracks.forEach((t) => t.stop());
    // Kept for the browser test that checks the camera is released.
    if (tracks.length && window.procfit) window.procfit.lastCameraTracks = tracks;
    this.stream = null;
    this.video.srcObject = null;
  }

  close() {
    // Released now, not when the dialog's close event comes (a task later); Escape closes
    // through that event.
    this.stop();
    this.dialog.close();
  }
}
